"""`afford train prediction`: the EM*D pathway on runs of 1-4 executions (paper II.C)."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np
import torch
from torch import nn
from torch.utils.data import DataLoader, WeightedRandomSampler

from afford.data.augment import AugmentConfig
from afford.data.format import Col, Dataset
from afford.data.torch_data import PredictionData, collate_prediction, worker_init
from afford.prediction.config import PRESETS, PredictionConfig
from afford.prediction.evaluate import CHANGED
from afford.prediction.model import PredictionNet
from afford.training.distributed import join_world, loader_order, rank_batch, rank_threads, to_device, wrap
from afford.training.loop import Loop, LoopState, run, warmup_cosine
from afford.training.signsgd import SignSGD

VAL_RUNS = 128  # validation runs per evaluation


def step_mask(steps: torch.Tensor, longest: int) -> torch.Tensor:
    """(B, L) 1 for the steps each run really has, 0 for padding."""
    return (torch.arange(longest, device=steps.device)[None, :] < steps[:, None]).float()


def change_mask(images: torch.Tensor, predicted: torch.Tensor, repair: bool) -> torch.Tensor:
    """(B, L, 1, H, W) 1 where the truth images[:, 1:] differs by more than CHANGED from each
    step's input: the true previous state, or with `repair` the step's real input (the true
    state at the first step, the previous prediction after)."""
    inputs = images[:, :-1]
    if repair:
        inputs = torch.cat([images[:, :1], predicted[:, :-1].detach()], 1)
    return ((images[:, 1:] - inputs).abs().amax(2, keepdim=True) > CHANGED).float()


def sequence_loss(net: nn.Module, images: torch.Tensor, actions: torch.Tensor, steps: torch.Tensor):
    """The training loss, mean over the real steps of the batch (padded steps are not run).

    The paper's is the squared error over the channels, mean over pixels (paper II.C). The
    config may add: the absolute error (sharper changes than the squared error's blur); the
    squared error of eq. (3)'s mask against where the truth changed; and the absolute error of
    D's new values against the truth where it changed. The last two reach D even where the
    mask is shut: through eq. (3) alone, a closed mask passes no gradient to the values it
    would let through, and values that never learn give the mask no reason to open.

    "Where it changed" is measured from the true previous state, or with `config.repair` from
    the step's own input (the previous prediction): then the mask is also taught to open, and
    D to redraw, where an earlier step left an error (a ghost, a blurred object), instead of
    being taught to keep such errors shut in, so they stop compounding through eq. (3).

    `net`: a PredictionNet, or one wrapped for DistributedDataParallel (called, not its methods).
    """
    c = getattr(net, "module", net).config
    with torch.autocast(images.device.type, dtype=torch.bfloat16, enabled=c.bf16):
        predicted, differences = net(images[:, 0], actions, steps)
    predicted, differences = predicted.float(), differences.float()
    truth = images[:, 1:]
    diff = predicted - truth
    err = c.loss_mse * (diff**2).sum(2).mean((-2, -1))  # (B, L)
    if c.loss_l1:
        err = err + c.loss_l1 * diff.abs().sum(2).mean((-2, -1))
    if c.loss_mask or c.loss_values:
        changed = change_mask(images, predicted, c.repair)
        if c.loss_mask:
            err = err + c.loss_mask * ((differences[:, :, -1:] - changed) ** 2).mean((-3, -2, -1))
        if c.loss_values:
            values = (differences[:, :, :-1] - truth).abs().sum(2, keepdim=True) * changed
            err = err + c.loss_values * values.sum((-3, -2, -1)) / changed.sum((-3, -2, -1)).clamp_min(1.0)
    mask = step_mask(steps, actions.shape[1])
    return (err * mask).sum() / mask.sum()


def turn_sampler(data: Dataset, indices: list[int], fraction: float, seed: int) -> WeightedRandomSampler:
    """Draws training runs so that `fraction` of them come from sequences holding a turn (read
    from the shards' small arrays, no images)."""
    from afford.data.format import shard_path, shard_summary
    from afford.sim.affordances import TYPES

    if not 0 < fraction < 1:
        raise ValueError(f"turn_fraction must lie between 0 and 1, not {fraction}")
    turn = TYPES.index("turn")
    has_turn = {}
    for k in range(data.manifest.n_shards):
        z = shard_summary(shard_path(data.root, k))
        ends = np.cumsum(z["state_count"] - 1)
        for i, stop, n in zip(z["index"], ends, z["state_count"] - 1, strict=True):
            has_turn[int(i)] = bool(np.any(z["actions"][stop - n : stop, Col.TYPE] == turn))
    with_turn = np.array([has_turn[i] for i in indices])
    if not with_turn.any() or with_turn.all():
        raise ValueError("turn_fraction needs training sequences both with and without a turn")
    weights = np.where(with_turn, fraction / with_turn.sum(), (1 - fraction) / (~with_turn).sum())
    return WeightedRandomSampler(
        torch.from_numpy(weights),
        len(indices),
        replacement=True,
        generator=torch.Generator().manual_seed(seed),
    )


def make_optimizer(net: PredictionNet, config: PredictionConfig) -> torch.optim.Optimizer:
    if config.optimizer == "signsgd":
        return SignSGD(net.parameters(), lr=config.lr)
    if config.optimizer == "adam":
        return torch.optim.Adam(net.parameters(), lr=config.lr)
    raise ValueError(f"unknown optimizer {config.optimizer!r}; expected signsgd or adam")


def train(
    data_dir: str | Path,
    config: PredictionConfig,
    run_dir: str | Path,
    progress: bool = True,
    init: str | Path | None = None,
    device: str = "auto",
) -> LoopState:
    """Train into `run_dir` (resuming from its last checkpoint); `init`: start a new run from
    another checkpoint's weights (fine-tuning), which must have the same architecture. Under
    torchrun, one rank of a DistributedDataParallel run; `device`: auto, cpu or cuda
    (`training/distributed.py`)."""
    world = join_world(device)
    torch.set_num_threads(rank_threads(config.threads, world))
    stream = config.seed * 1000 + world.rank  # each rank its own; rank 0 is a lone run's
    torch.manual_seed(stream)
    data = Dataset(data_dir)
    augment = AugmentConfig(
        shift_px=config.shift_px,
        mirror=config.mirror,
        angle_flip=config.angle_flip,
        position_noise=config.position_noise,
        angle_noise=config.angle_noise,
    )
    train_set = PredictionData(data, "train", config.max_steps, augment, seed=stream)
    if config.bootstrap:  # the same resample on every rank: it is drawn from the seed alone
        draw = np.random.default_rng(config.seed).integers(len(train_set), size=len(train_set))
        train_set.indices = [train_set.indices[k] for k in draw]
    sampler = (
        turn_sampler(data, train_set.indices, config.turn_fraction, stream) if config.turn_fraction else None
    )
    val_set = PredictionData(data, "val", config.max_steps, random_start=False)
    picks = np.linspace(0, len(val_set) - 1, min(VAL_RUNS, len(val_set))).astype(int)
    val_batch = to_device(collate_prediction([val_set[int(i)] for i in picks]), world.device)
    # Batches are built in a background process (decoding, augmenting, padding), so the
    # training threads never wait for them.
    workers = (
        {
            "num_workers": config.loader_workers,
            "worker_init_fn": worker_init,
            "persistent_workers": True,
            "prefetch_factor": 4,
        }
        if config.loader_workers
        else {}
    )
    loader = DataLoader(
        train_set,
        batch_size=rank_batch(config.batch_size, world),
        drop_last=True,
        collate_fn=collate_prediction,
        **loader_order(sampler, len(train_set), world, seed=config.seed),
        **workers,
    )
    net = PredictionNet(config).to(world.device)
    model = wrap(net, world, idle_parameters=True)
    opt = make_optimizer(net, config)

    def train_step(batch):
        loss = sequence_loss(model, *to_device(batch, world.device))
        return loss, {}

    def validate() -> dict[str, float]:
        images, actions, steps = val_batch
        predicted = net.rollout(images[:, 0], actions, steps)
        mask = step_mask(steps, actions.shape[1])[:, :, None, None]
        abs_err = (predicted - images[:, 1:]).abs().mean(2)  # (B, L, H, W)
        changed = ((images[:, 1:] - images[:, :-1]).abs().amax(2) > CHANGED) * mask
        return {
            "loss": float(sequence_loss(net, images, actions, steps)),
            "abs_error": float((abs_err * mask).sum() / (mask.sum() * abs_err[0, 0].numel())),
            "changed_abs_error": float((abs_err * changed).sum() / changed.sum().clamp_min(1)),
        }

    loop = Loop(
        kind="prediction",
        init=init,
        config=config,
        model=net,
        optimizer=opt,
        batches=loader,
        train_step=train_step,
        validate=validate,
        # The paper's schedule halves the lr on plateaus; a short CPU schedule ends better
        # on a cosine decay.
        lr_at=warmup_cosine(config.warmup, config.steps) if config.schedule == "cosine" else None,
        patience=config.patience if config.schedule == "plateau" else None,
        world=world,
    )
    return run(loop, run_dir, progress)


def config_for(preset: str, **overrides) -> PredictionConfig:
    return replace(PRESETS[preset], **{k: v for k, v in overrides.items() if v is not None})
