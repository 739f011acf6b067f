"""One training loop for both nets: progress bar, logs, checkpoints, resumption after a kill.

RUN/last.safetensors is rewritten at every evaluation (and on Ctrl-C); a re-run of the same
command loads it and continues from its step; a run without one starts from `Loop.init`'s
weights when given (fine-tuning). RUN/best.safetensors keeps the weights with the
lowest validation loss. RUN/config.json holds the config for people to read. Under torchrun
every rank runs this loop, and only rank 0 writes (`training/distributed.py`).
"""

from __future__ import annotations

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
    load_model_state,
    load_optimizer_state,
    read_checkpoint,
    save_checkpoint,
)
from afford.training.distributed import World, mean_over_ranks
from afford.training.log import NullLog, RunLog

LAST, BEST = "last.safetensors", "best.safetensors"


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
    config: object  # the net's config dataclass: steps, eval_every, log_every and lr come from it
    model: nn.Module
    optimizer: torch.optim.Optimizer
    batches: Iterable  # one epoch of batches; iterated again as needed
    train_step: Callable[[object], tuple[torch.Tensor, dict[str, float]]]
    validate: Callable[[], dict[str, float]]  # must contain "loss"
    lr_at: Callable[[int], float] | None = None  # lr multiplier by step (warm-up, cosine)
    patience: int | None = None  # halve the lr after this many evaluations without improvement
    init: str | Path | None = None  # a new run starts from these weights (fine-tuning)
    world: World = World()  # this process's rank among torchrun's; alone by default


def warmup_cosine(warmup: int, steps: int) -> Callable[[int], float]:
    """lr multiplier: linear warm-up, then a cosine down to 5% at the last step."""

    def factor(step: int) -> float:
        if step < warmup:
            return (step + 1) / warmup
        return 0.05 + 0.95 * 0.5 * (
            1 + math.cos(math.pi * min(1.0, (step - warmup) / max(steps - warmup, 1)))
        )

    return factor


def _forever(batches: Iterable) -> Iterator:
    while True:
        yield from batches


def run(loop: Loop, run_dir: str | Path, progress: bool = True) -> LoopState:
    from tqdm import tqdm

    run_dir = Path(run_dir)
    run_dir.mkdir(parents=True, exist_ok=True)
    config_dict = asdict(loop.config)
    state = LoopState()
    main = loop.world.main  # the one rank that writes
    log = RunLog(run_dir) if main else NullLog()
    if (run_dir / LAST).is_file():
        tensors, meta = read_checkpoint(run_dir / LAST, loop.kind)
        load_model_state(loop.model, tensors, run_dir / LAST)
        load_optimizer_state(loop.optimizer, tensors, meta)
        state = LoopState(**meta["extra"]["loop"])
        log.truncate_after(state.step)
    elif loop.init is not None:
        load_model_state(loop.model, read_checkpoint(loop.init, loop.kind)[0], loop.init)
    if main:
        (run_dir / "config.json").write_text(json.dumps({"kind": loop.kind, **config_dict}, indent=2) + "\n")

    def save(path: str) -> None:
        if not main:
            return
        save_checkpoint(
            run_dir / path,
            loop.model,
            loop.kind,
            config_dict,
            state.step,
            loop.optimizer,
            {"loop": asdict(state)},
        )

    def set_lr() -> None:
        scale = state.lr_scale * (loop.lr_at(state.step) if loop.lr_at else 1.0)
        for g in loop.optimizer.param_groups:
            g["lr"] = loop.config.lr * scale

    def evaluate() -> None:
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
                state.lr_scale /= 2  # the paper's schedule for the prediction nets
                state.evals_without_improvement = 0
        log.add(state.step, {f"val/{k}": v for k, v in values.items()})
        save(LAST)
        if improved:
            save(BEST)
        log.plot(f"{loop.kind}: {run_dir.name}")

    # `kill` (SIGTERM) stops like Ctrl-C, saving a checkpoint first; a background job started
    # from a script ignores SIGINT, so this is how such a run is stopped cleanly.
    previous = signal.signal(signal.SIGTERM, _interrupt)
    bar = tqdm(
        total=loop.config.steps,
        initial=state.step,
        disable=not (progress and main),
        desc=f"train {loop.kind}",
        unit="step",
    )
    loop.model.train()
    batches = _forever(loop.batches)
    t0, running = time.perf_counter(), {}
    try:
        while state.step < loop.config.steps:
            batch = next(batches)
            set_lr()
            loss, parts = loop.train_step(batch)
            loop.optimizer.zero_grad(set_to_none=True)
            loss.backward()
            loop.optimizer.step()
            state.step += 1
            for k, v in {"loss": float(loss.detach()), **parts}.items():
                running[k] = running.get(k, 0.0) + v
            if state.step % loop.config.log_every == 0:
                n = loop.config.log_every
                means = mean_over_ranks({k: v / n for k, v in running.items()}, loop.world)
                log.add(state.step, {f"train/{k}": v for k, v in means.items()} | {"lr": _lr(loop)})
                bar.set_postfix(loss=f"{means['loss']:.4f}")
                running = {}
            bar.update(1)
            if state.step % loop.config.eval_every == 0 or state.step == loop.config.steps:
                state.seconds += time.perf_counter() - t0
                t0 = time.perf_counter()
                evaluate()
    except KeyboardInterrupt:
        state.seconds += time.perf_counter() - t0
        save(LAST)
        raise
    finally:
        signal.signal(signal.SIGTERM, previous)
        bar.close()
        log.close()
    return state


def _interrupt(signum, frame) -> None:
    raise KeyboardInterrupt


def _lr(loop: Loop) -> float:
    return float(loop.optimizer.param_groups[0]["lr"])
