"""`afford train dynamics`: the object dynamics nets (P^a over objects) on true poses.

Examples are whole executions (`transitions.py`), from the train split of one dataset or
several; batches are drawn at random and encoded on the fly, which costs little beside the
nets. Validation is the val split's mixture loss. When training ends, the outcome head's
temperature is fitted on the val splits of every dataset (`calibration.py`) into
RUN/calibration.json, which loading the run's checkpoints and exporting them apply.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import torch

from afford.data.format import DataError
from afford.objects.calibration import TemperatureFit
from afford.objects.dynamics import (
    DynamicsConfig,
    ObjectDynamics,
    encode_inputs,
    encode_targets,
    mirror,
    mixture_loss,
)
from afford.objects.transitions import Transitions, read_transitions
from afford.training.checkpoint import BEST
from afford.training.loop import Loop, LoopState, run, warmup_cosine

KIND = "dynamics"
VAL_EXECUTIONS = 2000  # per evaluation: enough to follow the loss, a second on a CPU


def batch_of(t: Transitions, rows: np.ndarray, config: DynamicsConfig, rng: np.random.Generator | None):
    """Inputs and targets of the executions `rows`; with `rng`, mirrored at random and with
    noise on the input positions as the config asks (training only)."""
    before, after, actions, paths = t.before[rows], t.after[rows], t.actions[rows], t.paths[rows]
    if rng is not None and config.mirror:
        flip = rng.random(len(rows)) < 0.5
        mb, ma, mact, mp = mirror(before, after, actions, paths)
        before = np.where(flip[:, None, None], mb, before)
        after = np.where(flip[:, None, None], ma, after)
        actions = np.where(flip[:, None], mact, actions)
        paths = np.where(flip[:, None, None], mp, paths)
    seen = before
    if rng is not None and config.input_noise > 0:
        seen = before.copy()
        seen[..., :3] += rng.normal(0.0, config.input_noise, seen[..., :3].shape)
    inputs = encode_inputs(seen, t.held_before[rows], actions, paths if config.arm_path else None, config)
    targets = encode_targets(seen, after, t.held_after[rows], config)
    if config.arm_path:  # the recorded path is both an input and what the foresight learns
        targets["path"] = inputs["path"]
    return inputs, targets


def batch_rows(rng: np.random.Generator, n_true: int, n_all: int, batch: int, n_perceived: int) -> np.ndarray:
    """A batch's rows of a training set whose first `n_true` executions start from true states
    and the rest from perceived ones: `n_perceived` of them from the rest, drawn at random."""
    rows = rng.integers(0, n_true, batch - n_perceived)
    return np.concatenate([rows, rng.integers(n_true, n_all, n_perceived)]) if n_perceived else rows


def load(data_dirs: list[str | Path], split: str) -> Transitions:
    parts = [read_transitions(d, split) for d in data_dirs]
    t = Transitions.concatenate(parts)
    if len(t) == 0:
        raise DataError(f"{', '.join(map(str, data_dirs))}: no executions in the {split} split")
    return t


def load_perceived(data_dirs: list[str | Path], perception: str | Path, split: str | None) -> Transitions:
    """The executions of datasets with images, each started from the objects the perception net
    (a weights file) finds in its start image, as a planner starts: an object it
    misses (a support hidden under a block) is absent, and where it went is not learned. The
    objects it finds keep their true poses: the gate still learns that an object nothing moved
    stays exactly where it was, which a few millimetres of perceived error would blur. Found
    means matched to a true object within `perception_measure.MATCH_PX` of its centre, whatever
    kind perception gave it; what perception sees that is not there is dropped. Validation,
    the best checkpoint and the calibration stay on true starts."""
    from afford.data.format import Dataset
    from afford.objects.perception_measure import perceived_starts
    from afford.objects.perception_train import load_perception

    net = load_perception(perception)
    parts = []
    for d in data_dirs:
        t = read_transitions(d, split)
        seen, _ = perceived_starts(net, Dataset(d), t)
        missed = np.isnan(seen[..., :1])
        t.before = np.where(missed, np.nan, t.before).astype(t.before.dtype)
        rows = np.arange(len(t))
        held = t.held_before.astype(np.int64)
        t.held_before = np.where((held >= 0) & ~missed[rows, np.maximum(held, 0), 0], held, -1).astype(
            t.held_before.dtype
        )
        parts.append(t)
    return Transitions.concatenate(parts)


def train(
    data_dirs: list[str | Path],
    config: DynamicsConfig,
    run_dir: str | Path,
    progress: bool = True,
    limit: float | None = None,
    perceived_dirs: list[str | Path] = (),
    perception: str | Path | None = None,
    init: str | Path | None = None,
) -> LoopState:
    """Train into `run_dir` (resuming from its last checkpoint) on the train splits of
    `data_dirs`, validating on the first's val split; `limit`: use only this share of the
    training executions (a learning curve). With `perceived_dirs`, `config.perceived_share` of
    each batch comes from their executions started from what the `perception` net (a weights
    file, needed with them) sees (`load_perceived`);
    `init`: a new run starts from these weights (fine-tuning)."""
    torch.set_num_threads(config.threads)
    torch.manual_seed(config.seed)
    rng = np.random.default_rng(config.seed)
    train_set = load(data_dirs, "train")
    if limit is not None:
        keep = np.random.default_rng(0).permutation(len(train_set))[: max(1, int(limit * len(train_set)))]
        train_set = train_set.subset(np.sort(keep))
    n_true = len(train_set)
    n_perceived = 0
    if perceived_dirs:
        if not 0 < config.perceived_share < 1:
            raise DataError(f"perceived_share must be in (0, 1), not {config.perceived_share}")
        if perception is None:
            raise DataError("perceived datasets need the perception net that sees them")
        seen = load_perceived(list(perceived_dirs), perception, "train")
        if len(seen) == 0:
            raise DataError(f"{', '.join(map(str, perceived_dirs))}: no executions in the train split")
        train_set = Transitions.concatenate([train_set, seen])
        n_perceived = max(1, round(config.batch * config.perceived_share))
    val_set = load(data_dirs[:1], "val")
    val_rows = np.linspace(0, len(val_set) - 1, min(VAL_EXECUTIONS, len(val_set))).astype(int)
    val_batch = batch_of(val_set, val_rows, config, None)
    net = ObjectDynamics(config)
    opt = torch.optim.AdamW(net.parameters(), lr=config.lr, weight_decay=1e-4)

    class Batches:
        def __iter__(self):
            for _ in range(max(1, n_true // config.batch)):
                rows = batch_rows(rng, n_true, len(train_set), config.batch, n_perceived)
                yield batch_of(train_set, rows, config, rng)

    def train_step(batch):
        inputs, targets = batch
        return mixture_loss(net(inputs), targets, config.spread, config.rare_weight)

    def validate() -> dict[str, float]:
        loss, parts = mixture_loss(net(val_batch[0]), val_batch[1], config.spread, config.rare_weight)
        return {"loss": float(loss), **parts}

    loop = Loop(
        kind=KIND,
        config=config,
        model=net,
        optimizer=opt,
        batches=Batches(),
        train_step=train_step,
        validate=validate,
        lr_at=warmup_cosine(config.warmup, config.steps),
        init=init,
    )
    state = run(loop, run_dir, progress)
    (Path(run_dir) / "data.txt").write_text(
        "".join(f"{d}\n" for d in data_dirs)
        + "".join(f"{d} (from perceived starts)\n" for d in perceived_dirs)
        + f"training executions: {len(train_set)}\n"
    )
    calibrate(run_dir, data_dirs)
    return state


def calibrate(run_dir: str | Path, data_dirs: list[str | Path]) -> TemperatureFit:
    """Fit the outcome head's temperature of RUN/best.safetensors on the val splits of
    `data_dirs` into RUN/calibration.json (a re-run of a finished training does only this)."""
    from afford.objects.calibration import fit_temperature, logits_and_shares, write_calibration
    from afford.training.checkpoint import load_net_from_checkpoint

    net, _, meta = load_net_from_checkpoint(Path(run_dir) / BEST, KIND, DynamicsConfig, ObjectDynamics)
    fit = fit_temperature(*logits_and_shares(net, load(data_dirs, "val")))
    fit.step = int(meta["step"])
    write_calibration(run_dir, fit)
    return fit


def load_dynamics(path: str | Path, calibrated: bool = True) -> ObjectDynamics:
    """A trained dynamics net from a checkpoint or shipped weights file; a training run's
    checkpoint takes the outcome temperature its run's calibration.json fitted to that very
    checkpoint (its step), if any; an exported file has its own in its config."""
    from afford.objects.calibration import read_calibration
    from afford.training.checkpoint import load_net_from_checkpoint

    net, _, meta = load_net_from_checkpoint(path, KIND, DynamicsConfig, ObjectDynamics)
    if calibrated and "exported_from" not in meta.get("extra", {}):
        for name, value in read_calibration(Path(path).parent, step=meta.get("step")).items():
            setattr(net.config, name, value)
    return net
