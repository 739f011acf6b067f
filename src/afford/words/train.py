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
from afford.metrics import roc_auc
from afford.training.loop import LoopState, cosine_loop, run
from afford.words.config import AgreementConfig
from afford.words.data import ClauseBatch, ClauseData, collate_clauses
from afford.words.model import AgreementNet
from afford.words.sentences import vocabulary

VAL_DRAWS = 512  # clauses of the validation set, drawn once


def grounding_loss(maps: torch.Tensor, places: torch.Tensor) -> torch.Tensor:
    """Cross-entropy of the readout's map logits (B, 2, h*w) against where the clause's objects
    are (places (B, 2, h, w), each map a bump summing to 1, or zeros where there is none to
    find), over the maps that have one."""
    target = places.flatten(2)
    found = target.sum(-1) > 0
    if not found.any():
        return maps.sum() * 0.0
    ce = -(target * torch.log_softmax(maps, -1)).sum(-1)
    return ce[found].mean()


def fixed_draws(data: ClauseData, n: int, seed: int) -> ClauseBatch:
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
    val = fixed_draws(ClauseData(data, "val"), VAL_DRAWS, config.seed)
    net = AgreementNet(config)
    val_ids = net.token_ids(val.texts)
    opt = torch.optim.AdamW(net.parameters(), lr=config.lr, weight_decay=config.weight_decay)
    bce = nn.BCEWithLogitsLoss()

    def train_step(batch: ClauseBatch):
        grid = net.read(batch.images)
        logits, maps = net.judge_and_attend(grid, net.token_ids(batch.texts))
        clauses = bce(logits, batch.truths)
        loss, parts = clauses, {"clauses": float(clauses.detach())}
        if config.loss_objects:
            objects = bce(net.objects(grid), batch.objects)  # the stem taught to see the objects
            loss = loss + config.loss_objects * objects
            parts["objects"] = float(objects.detach())
        if config.loss_ground:
            ground = grounding_loss(maps, batch.places)
            loss = loss + config.loss_ground * ground
            parts["ground"] = float(ground.detach())
        return loss, parts

    def validate() -> dict[str, float]:
        logits = torch.cat(
            [net(val.images[i : i + 128], val_ids[i : i + 128]) for i in range(0, len(val_ids), 128)]
        )
        return {
            "loss": float(bce(logits, val.truths)),
            "accuracy": float(((logits > 0).float() == val.truths).float().mean()),
            "auc": roc_auc(logits.numpy(), val.truths.numpy()),
        }

    loop = cosine_loop("agreement", config, net, opt, loader, train_step, validate, init)
    return run(loop, run_dir, progress)
