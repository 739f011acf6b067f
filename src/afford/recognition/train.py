"""`afford train recognition`: the recognition net on a generated dataset."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import torch
from torch.utils.data import ConcatDataset, DataLoader

from afford.data.augment import AugmentConfig
from afford.data.format import Dataset
from afford.data.predicted import PredictedStates, mixed_sampler
from afford.data.torch_data import RecognitionData, collate_recognition
from afford.metrics import Tally
from afford.recognition.config import RecognitionConfig
from afford.recognition.model import RecognitionNet
from afford.recognition.targets import build_targets, decode, loss, suppress
from afford.sim.affordances import Affordance
from afford.training.distributed import join_world, loader_order, rank_batch, rank_threads, to_device, wrap
from afford.training.loop import LoopState, cosine_loop, run

VAL_IMAGES = 256  # validation images per evaluation: enough to follow recall, quick on a CPU


def rows_to_affordances(rows: torch.Tensor | np.ndarray) -> list[Affordance]:
    from afford.sim.affordance import decode_affordance

    return [decode_affordance(np.asarray(r)) for r in rows]


def train(
    data_dir: str | Path,
    config: RecognitionConfig,
    run_dir: str | Path,
    progress: bool = True,
    init: str | Path | None = None,
    predicted: str | Path | None = None,
    device: str = "auto",
) -> LoopState:
    """Train into `run_dir` (resuming from its last checkpoint); `init`: start a new run from
    another checkpoint's weights (fine-tuning), which must have the same architecture;
    `predicted`: a file of predicted states (`data/predicted.py`) that make up
    `config.predicted_fraction` of the batches, labelled by the true states' affordances.
    Under torchrun, one rank of a DistributedDataParallel run; `device`: auto, cpu or cuda
    (`training/distributed.py`)."""
    world = join_world(device)
    torch.set_num_threads(rank_threads(config.threads, world))
    stream = config.seed * 1000 + world.rank  # each rank its own; rank 0 is a lone run's
    torch.manual_seed(stream)
    data = Dataset(data_dir)
    augment = AugmentConfig(shift_px=config.shift_px, mirror=False, angle_flip=False)
    train_set = RecognitionData(data, "train", augment, seed=stream)
    val_set = RecognitionData(data, "val")
    n_val = min(VAL_IMAGES, len(val_set))
    val_images, val_rows = collate_recognition(
        [val_set[i] for i in np.linspace(0, len(val_set) - 1, n_val).astype(int)]
    )
    val_images, val_targets = (
        val_images.to(world.device),
        to_device(build_targets(val_rows, config), world.device),
    )
    sampler = None  # a shuffle
    if predicted is not None:
        futures = PredictedStates(predicted, data, augment, seed=stream)
        sampler = mixed_sampler(len(train_set), len(futures), config.predicted_fraction, seed=config.seed)
        train_set = ConcatDataset([train_set, futures])
    loader = DataLoader(
        train_set,
        batch_size=rank_batch(config.batch_size, world),
        drop_last=True,
        collate_fn=collate_recognition,
        **loader_order(sampler, len(train_set), world),
    )
    net = RecognitionNet(config).to(world.device)
    model = wrap(net, world)
    opt = torch.optim.AdamW(net.parameters(), lr=config.lr, weight_decay=config.weight_decay)

    def train_step(batch):
        images, rows = batch  # targets are built on the CPU, from the rows, then moved
        targets = to_device(build_targets(rows, config), world.device)
        return loss(model(images.to(world.device)), targets, config)

    def validate() -> dict[str, float]:
        raw = torch.cat([net(val_images[i : i + 64]) for i in range(0, len(val_images), 64)])
        total, parts = loss(raw, val_targets, config)
        tally = Tally()
        for dets, truth in zip(decode(raw.cpu(), config), val_rows, strict=True):
            tally.add(
                suppress(dets, config.suppress_radius, config.suppress_angle), rows_to_affordances(truth)
            )
        return {"loss": float(total), "recall": tally.recall, "spurious_per_image": tally.spurious_per_image}

    loop = cosine_loop("recognition", config, net, opt, loader, train_step, validate, init, world)
    return run(loop, run_dir, progress)
