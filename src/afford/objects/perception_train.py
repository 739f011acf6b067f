"""`afford train perception`: the object perception net on images with instance masks
(`afford generate --masks`)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import torch

from afford.data.format import DataError, Dataset
from afford.objects.perception import PerceptionConfig, PerceptionNet, fold_batch_norms, loss, targets
from afford.training.loop import LoopState, one_loss_loop, run

KIND = "perception"
VAL_IMAGES = 64


def states_of(data: Dataset, split: str | None) -> list[tuple[int, int]]:
    """Every (sequence, state) of a split (None: all); DataError if the dataset lacks masks."""
    if not data.manifest.generator.get("masks", False):
        raise DataError(
            f"{data.root}: no instance masks; make the dataset with `afford generate --masks` "
            "to train or measure perception"
        )
    return [(i, t) for i in data.indices(split) for t in range(data.sequence(i).length + 1)]


def batch_of(data: Dataset, items: list[tuple[int, int]], config: PerceptionConfig):
    seqs = [data.sequence(i) for i, _ in items]
    images = np.stack([s.image(t) for s, (_, t) in zip(seqs, items, strict=True)])
    masks = np.stack([s.masks[t] for s, (_, t) in zip(seqs, items, strict=True)])
    poses = np.stack([s.poses[t] for s, (_, t) in zip(seqs, items, strict=True)])
    held = np.array([s.held[t] for s, (_, t) in zip(seqs, items, strict=True)])
    x = torch.from_numpy(images.transpose(0, 3, 1, 2).copy()).contiguous(memory_format=torch.channels_last)
    return x, targets(masks, poses, held, config.sigma_px)


def train(
    data_dir: str | Path,
    config: PerceptionConfig,
    run_dir: str | Path,
    progress: bool = True,
    init: str | Path | None = None,
) -> LoopState:
    """Train into `run_dir`, resuming from its last checkpoint; a new run starts from `init`'s
    weights when given (a perception checkpoint: training on from where another run ended)."""
    torch.set_num_threads(config.threads)
    torch.manual_seed(config.seed)
    rng = np.random.default_rng(config.seed)
    data = Dataset(data_dir)
    train_items = states_of(data, "train")
    val_items = states_of(data, "val")
    val_items = [
        val_items[i] for i in np.linspace(0, len(val_items) - 1, min(VAL_IMAGES, len(val_items))).astype(int)
    ]
    val_batch = batch_of(data, val_items, config)
    net = PerceptionNet(config).to(memory_format=torch.channels_last)
    opt = torch.optim.AdamW(net.parameters(), lr=config.lr, weight_decay=config.weight_decay)

    class Batches:
        def __iter__(self):
            for _ in range(max(1, len(train_items) // config.batch)):
                picks = rng.integers(0, len(train_items), config.batch)
                yield batch_of(data, [train_items[i] for i in picks], config)

    def loss_of(batch):
        images, t = batch
        return loss(net(images), t)

    return run(one_loss_loop(KIND, config, net, opt, Batches(), loss_of, val_batch, init), run_dir, progress)


def load_perception(path: str | Path) -> PerceptionNet:
    from afford.training.checkpoint import load_net_from_checkpoint

    net, _, _ = load_net_from_checkpoint(path, KIND, PerceptionConfig, PerceptionNet)
    return fold_batch_norms(net).to(memory_format=torch.channels_last)
