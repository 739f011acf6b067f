"""`afford train prediction`: the EM*D pathway on runs of 1-4 executions (paper II.C)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import torch
from torch import nn
from torch.utils.data import DataLoader, WeightedRandomSampler

from afford.data.augment import AugmentConfig
from afford.data.effects import summary_effects
from afford.data.format import Dataset, shard_path, shard_summary
from afford.data.torch_data import JoinedData, PredictionData, collate_prediction, worker_init
from afford.prediction.config import PredictionConfig
from afford.prediction.evaluate import CHANGED
from afford.prediction.model import PredictionNet
from afford.training.distributed import join_world, loader_order, rank_batch, rank_threads, to_device, wrap
from afford.training.loop import Loop, LoopState, run, warmup_cosine
from afford.training.signsgd import SignSGD

VAL_RUNS = 128  # validation runs per evaluation


def step_mask(steps: torch.Tensor, longest: int) -> torch.Tensor:
    """(B, L) 1 for the steps each run really has, 0 for padding."""
    return (torch.arange(longest, device=steps.device)[None, :] < steps[:, None]).float()


def change_mask(images: torch.Tensor) -> torch.Tensor:
    """(B, L, 1, H, W) 1 where the truth images[:, 1:] differs by more than CHANGED from the
    true previous state."""
    return ((images[:, 1:] - images[:, :-1]).abs().amax(2, keepdim=True) > CHANGED).float()


def sequence_loss(
    net: nn.Module,
    images: torch.Tensor,
    actions: torch.Tensor,
    steps: torch.Tensor,
    effects: torch.Tensor | None = None,
):
    """The training loss, mean over the real steps of the batch (padded steps are not run).

    The paper's is the squared error over the channels, mean over pixels (paper II.C). The
    config may add: the absolute error (sharper changes than the squared error's blur); the
    squared error of eq. (3)'s mask against where the truth changed; and the absolute error of
    D's new values against the truth where it changed. The last two reach D even where the
    mask is shut: through eq. (3) alone, a closed mask passes no gradient to the values it
    would let through, and values that never learn give the mask no reason to open.

    `effects` (B, L, H, W): 1 on the pixels where each step had a side effect (data/effects.py);
    with hypotheses_by=effect they label which candidate each step carries on.

    `net`: a PredictionNet, or one wrapped for DistributedDataParallel (called, not its methods).
    """
    c = getattr(net, "module", net).config
    truth = images[:, 1:]
    many = c.outcomes.hypotheses > 1
    labels = None
    if many and c.outcomes.hypotheses_by == "effect" and effects is not None:  # else the winner
        labels = effects.flatten(2).any(-1)  # (B, L): the step had a side effect
    rolled = net(images[:, 0], actions, steps, truth if many else None, labels)
    predicted, differences, candidates = rolled.states, rolled.differences, rolled.candidates
    logits, picks = rolled.logits, rolled.picks
    diff = predicted - truth
    err = c.loss.mse * (diff**2).sum(2).mean((-2, -1))  # (B, L)
    if c.loss.l1:
        err = err + c.loss.l1 * diff.abs().sum(2).mean((-2, -1))
    if c.loss.mask or c.loss.values:
        changed = change_mask(images)
        if c.loss.mask:
            err = err + c.loss.mask * ((differences[:, :, -1:] - changed) ** 2).mean((-3, -2, -1))
        if c.loss.values:
            values = (differences[:, :, :-1] - truth).abs().sum(2, keepdim=True) * changed
            err = err + c.loss.values * values.sum((-3, -2, -1)) / changed.sum((-3, -2, -1)).clamp_min(1.0)
    if many:  # the terms above are the winner's (winner-takes-all); every candidate learns a little
        others = (candidates - truth[:, :, None]).abs().sum(3).mean((-2, -1))  # (B, L, K)
        err = err + c.loss.others * others.mean(-1)
        choice = nn.functional.cross_entropy(logits.flatten(0, 1), picks.flatten(), reduction="none")
        err = err + c.loss.choice * choice.view_as(err)
    mask = step_mask(steps, actions.shape[1])
    return (err * mask).sum() / mask.sum()


# What a training sequence can be drawn for (config `<name>_fraction`): a step that marks it.
STEP_MARKS = {
    "turn": lambda step: step.type == "turn",
    "effect": lambda step: not step.canonical,
    "place_effect": lambda step: step.type == "place" and not step.canonical,
}


def sequence_flags(data: Dataset) -> dict[str, dict[int, bool]]:
    """Per sequence index, whether a step of it is marked by each of STEP_MARKS (a turn, a side
    effect, a place with a side effect; data/effects.py), read from the shards' small arrays
    (no images)."""
    flags: dict[str, dict[int, bool]] = {what: {} for what in STEP_MARKS}
    for k in range(data.manifest.n_shards):
        z = shard_summary(shard_path(data.root, k))
        labels = summary_effects(z, data.slots)
        for i, steps in zip(z["index"], labels, strict=True):
            for what, marks in STEP_MARKS.items():
                flags[what][int(i)] = any(marks(s) for s in steps)
    return flags


def share_sampler(flags: dict[str, np.ndarray], shares: dict[str, float], seed: int) -> WeightedRandomSampler:
    """Draws runs so that `shares[what]` of them come from the sequences `flags[what]` marks
    and the rest from the sequences no flag marks. With two kinds asked, a sequence marked by
    both counts to both, so each share is then a floor."""
    for what, share in shares.items():
        if not 0 < share < 1:
            raise ValueError(f"{what}_fraction must lie between 0 and 1, not {share}")
        if not flags[what].any():
            raise ValueError(f"{what}_fraction needs training sequences with a {what}")
    if sum(shares.values()) >= 1:
        raise ValueError(f"the shares asked ({' + '.join(f'{w}_fraction' for w in shares)}) must sum below 1")
    rest = ~np.any([flags[what] for what in shares], axis=0)
    if not rest.any():
        kinds = " or ".join(shares)
        raise ValueError(f"the shares asked need training sequences without a {kinds}")
    weights = (1 - sum(shares.values())) * rest / rest.sum()
    for what, share in shares.items():
        weights = weights + share * flags[what] / flags[what].sum()
    return WeightedRandomSampler(
        torch.from_numpy(weights),
        len(rest),
        replacement=True,
        generator=torch.Generator().manual_seed(seed),
    )


def run_sampler(parts: list[PredictionData], config: PredictionConfig, seed: int):
    """The training runs' sampler over the runs of every part in turn: more turns
    (`sampling.turn_fraction`), more side effects (`effect_fraction`), more places with one
    (`place_effect_fraction`), any of them together, or None (runs as the data comes)."""
    asked = {what: getattr(config.sampling, f"{what}_fraction") for what in STEP_MARKS}
    asked = {what: share for what, share in asked.items() if share}
    if not asked:
        return None
    flags: dict[str, list[bool]] = {what: [] for what in asked}
    for part in parts:
        marks = sequence_flags(part.data)
        for what in asked:
            flags[what] += [marks[what][i] for i in part.indices]
    return share_sampler({what: np.array(f) for what, f in flags.items()}, asked, seed)


def make_optimizer(net: PredictionNet, config: PredictionConfig) -> torch.optim.Optimizer:
    params = list(net.parameters())
    if config.training.optimizer == "signsgd":
        return SignSGD(params, lr=config.training.lr)
    if config.training.optimizer == "adam":
        return torch.optim.Adam(params, lr=config.training.lr)
    raise ValueError(f"unknown optimizer {config.training.optimizer!r}; expected signsgd or adam")


def train(
    data_dir: str | Path,
    config: PredictionConfig,
    run_dir: str | Path,
    progress: bool = True,
    init: str | Path | None = None,
    device: str = "auto",
    more_data: tuple[str | Path, ...] = (),
) -> LoopState:
    """Train into `run_dir` (resuming from its last checkpoint); `init`: start a new run from
    another checkpoint's weights (fine-tuning), which must have the same architecture. Under
    torchrun, one rank of a DistributedDataParallel run; `device`: auto, cpu or cuda
    (`training/distributed.py`). `more_data`: datasets whose train splits join `data_dir`'s
    (validation stays on `data_dir`'s)."""
    world = join_world(device)
    torch.set_num_threads(rank_threads(config.training.threads, world))
    stream = config.sampling.seed * 1000 + world.rank  # each rank its own; rank 0 is a lone run's
    torch.manual_seed(stream)
    data = Dataset(data_dir)
    augment = AugmentConfig(
        shift_px=config.sampling.shift_px,
        mirror=config.sampling.mirror,
        angle_flip=config.sampling.angle_flip,
        position_noise=config.sampling.position_noise,
        angle_noise=config.sampling.angle_noise,
    )
    by_effect = config.outcomes.hypotheses > 1 and config.outcomes.hypotheses_by == "effect"
    parts = [
        PredictionData(
            d,
            "train",
            config.sampling.max_steps,
            augment,
            seed=[stream, j] if j else stream,
            effect_masks=by_effect,
        )
        for j, d in enumerate([data, *(Dataset(more) for more in more_data)])
    ]
    if config.sampling.bootstrap:  # the same resample on every rank: it is drawn from the seed alone
        rng = np.random.default_rng(config.sampling.seed)
        for part in parts:
            part.indices = [part.indices[k] for k in rng.integers(len(part), size=len(part))]
    train_set = parts[0] if len(parts) == 1 else JoinedData(parts)
    sampler = run_sampler(parts, config, stream)
    # Runs labelled by effect are validated by the same labels, so that the best checkpoint is
    # the one whose head and outcomes learned what training asks, not the one nearest the
    # winners (which a head trained alone drifts away from).
    val_set = PredictionData(
        data,
        "val",
        config.sampling.max_steps,
        random_start=False,
        effect_masks=by_effect,
    )
    picks = np.linspace(0, len(val_set) - 1, min(VAL_RUNS, len(val_set))).astype(int)
    val_batch = to_device(collate_prediction([val_set[int(i)] for i in picks]), world.device)
    # Batches are built in a background process (decoding, augmenting, padding), so the
    # training threads never wait for them.
    workers = (
        {
            "num_workers": config.training.loader_workers,
            "worker_init_fn": worker_init,
            "persistent_workers": True,
            "prefetch_factor": 4,
        }
        if config.training.loader_workers
        else {}
    )
    loader = DataLoader(
        train_set,
        batch_size=rank_batch(config.training.batch_size, world),
        drop_last=True,
        collate_fn=collate_prediction,
        **loader_order(sampler, len(train_set), world, seed=config.sampling.seed),
        **workers,
    )
    net = PredictionNet(config).to(world.device)
    opt = make_optimizer(net, config)
    model = wrap(net, world, idle_parameters=True)

    def train_step(batch):
        loss = sequence_loss(model, *to_device(batch, world.device))
        return loss, {}

    def validate() -> dict[str, float]:
        images, actions, steps = val_batch[:3]
        predicted = net.rollout(images[:, 0], actions, steps)
        mask = step_mask(steps, actions.shape[1])[:, :, None, None]
        abs_err = (predicted - images[:, 1:]).abs().mean(2)  # (B, L, H, W)
        changed = ((images[:, 1:] - images[:, :-1]).abs().amax(2) > CHANGED) * mask
        return {
            "loss": float(sequence_loss(net, *val_batch)),
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
        lr_at=warmup_cosine(config.training.warmup, config.training.steps)
        if config.training.schedule == "cosine"
        else None,
        patience=config.training.patience if config.training.schedule == "plateau" else None,
        world=world,
    )
    return run(loop, run_dir, progress)
