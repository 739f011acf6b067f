"""`afford bench random`: random tasks planned by every planner, over parallel workers.

Each worker process owns a `Scene` (and a bundle of nets, each loaded once) and takes task seeds
in turn; the caller keeps the first `n` seeds that make a task, in seed order, so the set of
tasks does not depend on the number of workers. The oracle's tree is bounded in time: past the
limit it plans from the states grown so far (and the row says so). Success rates come with
Wilson 95% intervals.
"""

from __future__ import annotations

import math
import multiprocessing as mp
from collections import deque
from collections.abc import Iterator
from dataclasses import dataclass, field, replace

import numpy as np

from afford.planning.run import PlannerConfig, solve
from afford.shipped import Nets

Z95 = 1.959964  # two-sided 95% normal quantile
ORACLE_BATCH = 8  # the oracle's predict batch: small, so its time limit is checked often


@dataclass(frozen=True)
class BenchSpec:
    max_steps: int
    planners: tuple[str, ...]
    weights: str | None = None  # the planners' weights folder (None: the package's)
    prediction: str | None = None  # a prediction net in place of the folder's (`shipped.Nets`)
    time_limit: float | None = 60.0  # seconds of tree search per task and planner
    threads: int = 1  # torch threads per worker
    min_steps: int = 1
    planner: PlannerConfig = field(default_factory=PlannerConfig)  # the search's strategy and budget too


def wilson(successes: float, n: int) -> tuple[float, float]:
    """Wilson score 95% interval for a success rate. A fractional count (the symbolic planner's
    expected successes over its equally short plans) is used as is: its variance is at most a
    binomial's, so the interval is conservative for it."""
    if n == 0:
        return 0.0, 1.0
    p = successes / n
    denom = 1 + Z95**2 / n
    centre = (p + Z95**2 / (2 * n)) / denom
    half = Z95 * math.sqrt(p * (1 - p) / n + Z95**2 / (4 * n * n)) / denom
    return max(0.0, centre - half), min(1.0, centre + half)


_state: dict = {}


def _init(spec: BenchSpec) -> None:
    import torch

    from afford.sim.scene import Scene

    torch.set_num_threads(spec.threads)
    _state["spec"] = spec
    _state["scene"] = Scene()
    _state["nets"] = Nets(spec.weights, spec.prediction)


def run_seed(seed: int) -> dict | None:
    """Plan the random task of `seed` with every planner (in a worker): its row, or None when
    the seed makes no task."""
    from afford.planning.random_tasks import random_task

    spec: BenchSpec = _state["spec"]
    scene = _state["scene"]
    task = random_task(scene, seed, spec.max_steps, spec.min_steps)
    if task is None:
        return None
    row: dict = {"task": task.name, "seed": seed, "steps": task.max_steps}
    for planner in spec.planners:
        batch = ORACLE_BATCH if planner.endswith("oracle") else spec.planner.search.batch_size
        search = replace(spec.planner.search, progress=False, time_limit=spec.time_limit, batch_size=batch)
        config = replace(spec.planner, search=search)
        o = solve(task, planner, scene, config, _state["nets"])
        row[planner] = {
            "solved": o.success,
            "score": o.success_rate if o.success_rate is not None else float(o.success),
            "plan_length": len(o.plan or ()),
            "seconds": round(o.seconds, 2),
            "truncated": o.truncated,
            "nodes": o.nodes,
        } | ({"source": o.source} if o.source else {})
    return row


def run(spec: BenchSpec, n: int, first_seed: int, workers: int) -> Iterator[dict]:
    """Rows of the first `n` seeds from `first_seed` that make a task, in seed order."""
    if workers <= 1:
        _init(spec)
        seed, made = first_seed, 0
        while made < n:
            row = run_seed(seed)
            seed += 1
            if row is not None:
                made += 1
                yield row
        return
    ctx = mp.get_context("spawn")  # each worker makes its own renderer and threads
    with ctx.Pool(workers, initializer=_init, initargs=(spec,)) as pool:
        # A few seeds in flight per worker, taken back in seed order.
        pending: deque = deque()
        seed, made = first_seed, 0
        while made < n:
            while len(pending) < 2 * workers:
                pending.append(pool.apply_async(run_seed, (seed,)))
                seed += 1
            row = pending.popleft().get()
            if row is not None:
                made += 1
                yield row
        pool.terminate()


def summarise(rows: list[dict], planners: tuple[str, ...]) -> dict:
    """Per planner: success rate (mean score), its interval, mean planning seconds, and how
    many trees the time limit cut."""
    out = {}
    for p in planners:
        scores = [r[p]["score"] for r in rows]
        lo, hi = wilson(float(np.sum(scores)), len(rows))
        out[p] = {
            "success": round(float(np.mean(scores)), 4),
            "ci95": [round(lo, 4), round(hi, 4)],
            "seconds": round(float(np.mean([r[p]["seconds"] for r in rows])), 2),
            "truncated": int(sum(r[p]["truncated"] for r in rows)),
            "nodes": round(float(np.mean([r[p].get("nodes", 0) for r in rows])), 1),
        }
        sources = [r[p]["source"] for r in rows if "source" in r[p]]
        if sources:
            out[p]["from_symbolic"] = sources.count("symbolic")
    if "learned" in planners and "oracle" in planners and out["oracle"]["success"] > 0:
        out["learned"]["of_oracle"] = round(out["learned"]["success"] / out["oracle"]["success"], 4)
    return out
