"""`afford train goals`: the agreement model on clauses sampled about true and predicted states."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np
import torch
from torch import nn
from torch.utils.data import DataLoader

from afford.data.augment import AugmentConfig
from afford.data.format import Dataset
from afford.data.predicted import PredictedStates, mixed_sampler
from afford.training.distributed import World
from afford.training.loop import Loop, LoopState, run, warmup_cosine
from afford.words.config import AgreementConfig
from afford.words.data import ClauseData, collate_clauses
from afford.words.metrics import roc_auc
from afford.words.model import AgreementNet
from afford.words.sentences import vocabulary

VAL_DRAWS = 512  # clauses of the validation set, drawn once


def fixed_draws(data: ClauseData, n: int, seed: int) -> tuple:
    """n draws of `data` made once, with their own stream: the same set at every evaluation."""
    data.rng = np.random.default_rng(seed)
    picks = np.random.default_rng(seed).integers(len(data), size=min(n, len(data)))
    return collate_clauses([data[int(k)] for k in picks])


def train(
    data_dir: str | Path,
    config: AgreementConfig,
    run_dir: str | Path,
    progress: bool = True,
    predicted: str | Path | None = None,
    init: str | Path | None = None,
) -> LoopState:
    """Train into `run_dir` (resuming from its last checkpoint); `predicted`: a file of
    predicted states (`afford data predict`), `config.predicted_fraction` of the draws."""
    torch.set_num_threads(config.threads)
    torch.manual_seed(config.seed)
    if not config.vocabulary:
        config = replace(config, vocabulary=tuple(vocabulary()))
    data = Dataset(data_dir)
    futures = None if predicted is None else PredictedStates(predicted, data)
    train_set = ClauseData(
        data,
        "train",
        futures,
        AugmentConfig(shift_px=config.shift_px, mirror=False),
        config.seed,
        config.grid,
    )
    sampler = None
    if futures is not None:
        sampler = mixed_sampler(train_set.real, len(futures), config.predicted_fraction, config.seed)
    loader = DataLoader(
        train_set,
        batch_size=config.batch_size,
        drop_last=True,
        collate_fn=collate_clauses,
        **({"sampler": sampler} if sampler is not None else {"shuffle": True}),
    )
    val_images, val_texts, val_truths, _, _ = fixed_draws(ClauseData(data, "val"), VAL_DRAWS, config.seed)
    net = AgreementNet(config)
    val_ids = net.token_ids(val_texts)
    opt = torch.optim.AdamW(net.parameters(), lr=config.lr, weight_decay=config.weight_decay)
    bce = nn.BCEWithLogitsLoss()

    def train_step(batch):
        images, texts, truths, _, maps = batch
        if not config.loss_objects:
            return bce(net(images, net.token_ids(texts)), truths), {}
        grid = net.read(images)
        clauses = bce(net.judge(grid, net.token_ids(texts)), truths)
        objects = bce(net.objects(grid), maps)  # the stem taught to see the objects
        return clauses + config.loss_objects * objects, {
            "clauses": float(clauses.detach()),
            "objects": float(objects.detach()),
        }

    def validate() -> dict[str, float]:
        logits = torch.cat(
            [net(val_images[i : i + 128], val_ids[i : i + 128]) for i in range(0, len(val_ids), 128)]
        )
        return {
            "loss": float(bce(logits, val_truths)),
            "accuracy": float(((logits > 0).float() == val_truths).float().mean()),
            "auc": roc_auc(logits.numpy(), val_truths.numpy()),
        }

    loop = Loop(
        kind="agreement",
        init=init,
        config=config,
        model=net,
        optimizer=opt,
        batches=loader,
        train_step=train_step,
        validate=validate,
        lr_at=warmup_cosine(config.warmup, config.steps),
        world=World(),
    )
    return run(loop, run_dir, progress)
