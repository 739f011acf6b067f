"""One training loop for both nets: progress bar, logs, checkpoints, resumption after a kill.

RUN/last.safetensors is rewritten at every evaluation (and on Ctrl-C); a re-run of the same
command loads it and continues from its step; a run without one starts from `Loop.init`'s
weights when given (fine-tuning). RUN/best.safetensors keeps the weights with the
lowest validation loss. RUN/config.json holds the config for people to read. Under torchrun
every rank runs this loop, and only rank 0 writes (`training/distributed.py`).
"""

from __future__ import annotations

import dataclasses
import json
import math
import signal
import time
from collections.abc import Callable, Iterable, Iterator
from dataclasses import asdict, dataclass, field
from pathlib import Path

import torch
from torch import nn

from afford.training.checkpoint import (
    BEST,
    LAST,
    load_model_state,
    load_optimizer_state,
    read_checkpoint,
    save_checkpoint,
)
from afford.training.distributed import World, mean_over_ranks
from afford.training.log import NullLog, RunLog


@dataclass
class LoopState:
    step: int = 0
    best: float = float("inf")
    evals_without_improvement: int = 0
    lr_scale: float = 1.0
    seconds: float = 0.0  # training time summed over resumptions
    extra: dict = field(default_factory=dict)


@dataclass
class Loop:
    kind: str  # "recognition" or "prediction"
    config: object  # the net's config dataclass, saved with every checkpoint
    model: nn.Module
    optimizer: torch.optim.Optimizer
    batches: Iterable  # one epoch of batches; iterated again as needed
    train_step: Callable[[object], tuple[torch.Tensor, dict[str, float]]]
    validate: Callable[[], dict[str, float]]  # must contain "loss"
    lr_at: Callable[[int], float] | None = None  # lr multiplier by step (warm-up, cosine)
    patience: int | None = None  # halve the lr after this many evaluations without improvement
    init: str | Path | None = None  # a new run starts from these weights (fine-tuning)
    world: World = World()  # this process's rank among torchrun's; alone by default

    @property
    def plan(self):
        """The record with steps, eval_every, log_every, lr (and grad_clip, if any): the config's
        `training` record where it groups its fields (training/fields.py), else the config."""
        training = getattr(self.config, "training", None)
        return training if dataclasses.is_dataclass(training) else self.config


def warmup_cosine(warmup: int, steps: int) -> Callable[[int], float]:
    """lr multiplier: linear warm-up, then a cosine down to 5% at the last step."""

    def factor(step: int) -> float:
        if step < warmup:
            return (step + 1) / warmup
        return 0.05 + 0.95 * 0.5 * (
            1 + math.cos(math.pi * min(1.0, (step - warmup) / max(steps - warmup, 1)))
        )

    return factor


def cosine_loop(
    kind: str,
    config,
    model: nn.Module,
    optimizer: torch.optim.Optimizer,
    batches: Iterable,
    train_step: Callable[[object], tuple[torch.Tensor, dict[str, float]]],
    validate: Callable[[], dict[str, float]],
    init: str | Path | None = None,
    world: World | None = None,
) -> Loop:
    """A loop on a warm-up and cosine schedule (the config's `warmup` and `steps`): every net's
    but the prediction net's, whose presets may halve the rate on a plateau instead."""
    return Loop(
        kind=kind,
        config=config,
        model=model,
        optimizer=optimizer,
        batches=batches,
        train_step=train_step,
        validate=validate,
        lr_at=warmup_cosine(config.warmup, config.steps),
        init=init,
        world=World() if world is None else world,
    )


def one_loss_loop(
    kind: str,
    config,
    model: nn.Module,
    optimizer: torch.optim.Optimizer,
    batches: Iterable,
    loss_of: Callable[[object], tuple[torch.Tensor, dict[str, float]]],
    val_batch,
    init: str | Path | None = None,
) -> Loop:
    """A loop on a warm-up and cosine schedule (the config's `warmup` and `steps`) whose training
    step and validation are one loss: `loss_of(batch)` -> (loss, its parts), validated on
    `val_batch`."""

    def validate() -> dict[str, float]:
        loss, parts = loss_of(val_batch)
        return {"loss": float(loss), **parts}

    return cosine_loop(kind, config, model, optimizer, batches, loss_of, validate, init)


def _forever(batches: Iterable) -> Iterator:
    while True:
        yield from batches


class _Run:
    """One call of `run`: the loop, its folder, its state and log, and the steps it takes."""

    def __init__(self, loop: Loop, run_dir: Path):
        self.loop, self.dir = loop, run_dir
        self.main = loop.world.main  # the one rank that writes
        self.log = RunLog(run_dir) if self.main else NullLog()
        self.config = asdict(loop.config)
        self.state = LoopState()
        self.running: dict[str, float] = {}

    def start(self) -> None:
        """Resume from RUN/last.safetensors, or start from `loop.init`'s weights, or afresh."""
        loop, last = self.loop, self.dir / LAST
        if last.is_file():
            tensors, meta = read_checkpoint(last, loop.kind)
            load_model_state(loop.model, tensors, last)
            load_optimizer_state(loop.optimizer, tensors, meta)
            self.state = LoopState(**meta["extra"]["loop"])
            self.log.truncate_after(self.state.step)
        elif loop.init is not None:
            load_model_state(loop.model, read_checkpoint(loop.init, loop.kind)[0], loop.init)
        if self.main:
            record = {"kind": loop.kind, **self.config}
            (self.dir / "config.json").write_text(json.dumps(record, indent=2) + "\n")

    def save(self, name: str) -> None:
        if self.main:
            loop, state = self.loop, self.state
            extra = {"loop": asdict(state)}
            save_checkpoint(
                self.dir / name, loop.model, loop.kind, self.config, state.step, loop.optimizer, extra
            )

    def step(self, batch) -> float:
        """One optimiser step at the scheduled rate; the batch's loss."""
        loop, state = self.loop, self.state
        scale = state.lr_scale * (loop.lr_at(state.step) if loop.lr_at else 1.0)
        for g in loop.optimizer.param_groups:
            g["lr"] = loop.plan.lr * scale
        loss, parts = loop.train_step(batch)
        loop.optimizer.zero_grad(set_to_none=True)
        loss.backward()
        clip = getattr(loop.plan, "grad_clip", 0.0)
        if clip:  # one wild batch must not poison Adam's second moments for thousands of steps
            torch.nn.utils.clip_grad_norm_(loop.model.parameters(), clip)
        loop.optimizer.step()
        state.step += 1
        for k, v in {"loss": float(loss.detach()), **parts}.items():
            self.running[k] = self.running.get(k, 0.0) + v
        return float(loss.detach())

    def log_running(self) -> float:
        """Log the mean of the last `log_every` steps (over every rank); the mean loss."""
        n = self.loop.plan.log_every
        means = mean_over_ranks({k: v / n for k, v in self.running.items()}, self.loop.world)
        self.log.add(self.state.step, {f"train/{k}": v for k, v in means.items()} | {"lr": _lr(self.loop)})
        self.running = {}
        return means["loss"]

    def evaluate(self) -> None:
        """Validate, keep the best weights, halve the rate on a plateau (the paper's schedule)."""
        loop, state = self.loop, self.state
        loop.model.eval()
        with torch.no_grad():
            values = loop.validate()
        loop.model.train()
        improved = values["loss"] < state.best
        if improved:
            state.best, state.evals_without_improvement = values["loss"], 0
        else:
            state.evals_without_improvement += 1
            if loop.patience and state.evals_without_improvement >= loop.patience:
                state.lr_scale /= 2
                state.evals_without_improvement = 0
        self.log.add(state.step, {f"val/{k}": v for k, v in values.items()})
        self.save(LAST)
        if improved:
            self.save(BEST)
        self.log.plot(f"{loop.kind}: {self.dir.name}")


def run(loop: Loop, run_dir: str | Path, progress: bool = True) -> LoopState:
    """Train to `loop.plan.steps`, resuming where RUN/last.safetensors left off."""
    from tqdm import tqdm

    run_dir = Path(run_dir)
    run_dir.mkdir(parents=True, exist_ok=True)
    this = _Run(loop, run_dir)
    this.start()
    state, config = this.state, loop.plan
    # `kill` (SIGTERM) stops like Ctrl-C, saving a checkpoint first; a background job started
    # from a script ignores SIGINT, so this is how such a run is stopped cleanly.
    previous = signal.signal(signal.SIGTERM, _interrupt)
    quiet = not (progress and this.main)
    bar = tqdm(total=config.steps, initial=state.step, disable=quiet, desc=f"train {loop.kind}", unit="step")
    loop.model.train()
    batches = _forever(loop.batches)
    t0 = time.perf_counter()
    try:
        while state.step < config.steps:
            this.step(next(batches))
            if state.step % config.log_every == 0:
                bar.set_postfix(loss=f"{this.log_running():.4f}")
            bar.update(1)
            if state.step % config.eval_every == 0 or state.step == config.steps:
                state.seconds += time.perf_counter() - t0
                t0 = time.perf_counter()
                this.evaluate()
    except KeyboardInterrupt:
        state.seconds += time.perf_counter() - t0
        this.save(LAST)
        raise
    finally:
        signal.signal(signal.SIGTERM, previous)
        bar.close()
        this.log.close()
        stop_workers(loop.batches)
    return state


def stop_workers(batches: Iterable) -> None:
    """End a DataLoader's persistent workers now. It keeps them until it is deleted, which at
    interpreter exit comes after multiprocessing's own clean-up; that terminates and waits on
    them, and workers deaf to SIGTERM (data/torch_data.worker_init) would keep the finished
    run's process waiting for ever."""
    iterator = getattr(batches, "_iterator", None)
    if iterator is not None and hasattr(iterator, "_shutdown_workers"):
        iterator._shutdown_workers()
        batches._iterator = None


def _interrupt(signum, frame) -> None:
    raise KeyboardInterrupt


def _lr(loop: Loop) -> float:
    return float(loop.optimizer.param_groups[0]["lr"])
