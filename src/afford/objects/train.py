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
    mixture_loss,
)
from afford.objects.transitions import Transitions, read_transitions
from afford.training.checkpoint import BEST
from afford.training.loop import LoopState, one_loss_loop, run

KIND = "dynamics"
VAL_EXECUTIONS = 2000  # per evaluation: enough to follow the loss, a second on a CPU


def batch_of(t: Transitions, rows: np.ndarray, config: DynamicsConfig):
    """Inputs and targets of the executions `rows`."""
    before = t.before[rows]
    inputs = encode_inputs(before, t.held_before[rows], t.actions[rows])
    return inputs, encode_targets(before, t.after[rows], t.held_after[rows], config)


def load(data_dirs: list[str | Path], split: str) -> Transitions:
    parts = [read_transitions(d, split) for d in data_dirs]
    t = Transitions.concatenate(parts)
    if len(t) == 0:
        raise DataError(f"{', '.join(map(str, data_dirs))}: no executions in the {split} split")
    return t


def train(
    data_dirs: list[str | Path],
    config: DynamicsConfig,
    run_dir: str | Path,
    progress: bool = True,
    limit: float | None = None,
    init: str | Path | None = None,
) -> LoopState:
    """Train into `run_dir` (resuming from its last checkpoint) on the train splits of
    `data_dirs`, validating on the first's val split; `limit`: use only this share of the
    training executions (a learning curve); `init`: a new run starts from these weights
    (fine-tuning)."""
    torch.set_num_threads(config.threads)
    torch.manual_seed(config.seed)
    rng = np.random.default_rng(config.seed)
    train_set = load(data_dirs, "train")
    if limit is not None:
        keep = np.random.default_rng(0).permutation(len(train_set))[: max(1, int(limit * len(train_set)))]
        train_set = train_set.subset(np.sort(keep))
    val_set = load(data_dirs[:1], "val")
    val_rows = np.linspace(0, len(val_set) - 1, min(VAL_EXECUTIONS, len(val_set))).astype(int)
    val_batch = batch_of(val_set, val_rows, config)
    net = ObjectDynamics(config)
    opt = torch.optim.AdamW(net.parameters(), lr=config.lr, weight_decay=1e-4)

    class Batches:
        def __iter__(self):
            for _ in range(max(1, len(train_set) // config.batch)):
                yield batch_of(train_set, rng.integers(0, len(train_set), config.batch), config)

    def loss_of(batch):
        inputs, targets = batch
        return mixture_loss(net(inputs), targets, config.spread)

    loop = one_loss_loop(KIND, config, net, opt, Batches(), loss_of, val_batch, init)
    state = run(loop, run_dir, progress)
    (Path(run_dir) / "data.txt").write_text(
        "".join(f"{d}\n" for d in data_dirs) + f"training executions: {len(train_set)}\n"
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
