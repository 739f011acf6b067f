"""Dataset generation (paper III.B): random scenes, random affordance executions, in parallel.

Sequence i draws everything from its own generator seeded by (seed, i), and the simulator is
reset before it, so its content does not depend on the worker that makes it. Workers write
whole shards atomically (see format.py); a re-run makes only the shards still missing.
The shards are handed out by an executor: a local process pool here, or Ray tasks on a local
instance or a cluster (`data/ray_executor.py`); both run the same `shard.make_shard`.
"""

from __future__ import annotations

import multiprocessing as mp
import time
from collections.abc import Callable, Iterator
from dataclasses import asdict, dataclass, field
from pathlib import Path

from afford.data.draws import DRAWS
from afford.data.format import (
    SHARD_DIR,
    DataError,
    Manifest,
    check_shard,
    default_splits,
    read_manifest,
    shard_path,
    shard_status,
    write_manifest,
)
from afford.data.ray_executor import run_on_ray
from afford.data.shard import TURN_ANGLES, ShardJob, ShardResult, make_shard
from afford.sim.layout import LAYOUTS
from afford.sim.mjcf import slot_names


@dataclass(frozen=True)
class GenerateConfig:
    sequences: int
    seed: int = 0
    workers: int = 2
    shard_size: int = 25  # ~10 s of work per shard on one core: little lost to a kill
    max_steps: int = 4  # executions per sequence (paper III.B)
    # "quarter": each drawn turn is +90 or -90 (the paper's); "continuous": the turn's angle is
    # drawn from [-180, 180] (paper V), for a prediction net that learns any angle.
    turn_angles: str = "quarter"
    # How each step picks its execution (a key of draws.DRAWS): "uniform", the paper's; or
    # "effects", which seeks side effects at every step (our option, not the paper's data).
    actions_drawn: str = "uniform"
    # The arrangements scenes are drawn from (a key of layout.LAYOUTS): "default", or
    # "balances", the block on one support far off its centre (our option, not the paper's).
    layout: str = "default"
    # False: poses, held objects, affordance lists and arm paths, no images (`--poses-only`):
    # the data the object world model's dynamics learn from, made without rendering.
    images: bool = True
    # True: each state also keeps its instance mask (the slot seen per pixel), which the object
    # perception net learns from (`--masks`).
    masks: bool = False
    # The val and test splits of a dataset of this many sequences (None: of this one's), e.g. the
    # first 5,200 sequences of the default dataset with its 188 + 188 held out (`--splits-of`).
    splits_of: int | None = None
    executor: str = "local"  # a key of EXECUTORS
    address: str | None = None  # the Ray cluster to join (executor "ray"); None: a local instance


@dataclass
class GenerateReport:
    sequences: int
    made_shards: int
    skipped_shards: int
    executions: int  # made by this run
    failed_executions: int  # drawn but not executable by the arm (re-drawn)
    seconds: float
    remade: list[str] = field(default_factory=list)  # shards that failed their check, made again

    @property
    def executions_per_second(self) -> float:
        return self.executions / self.seconds if self.seconds > 0 else 0.0


def run_local(jobs: list[ShardJob], config: GenerateConfig) -> Iterator[ShardResult]:
    """The jobs in this process, or in a pool of `config.workers` fresh interpreters."""
    if config.workers <= 1 or len(jobs) <= 1:
        yield from map(make_shard, jobs)
        return
    ctx = mp.get_context("spawn")  # a fresh interpreter per worker: no GL state inherited
    with ctx.Pool(min(config.workers, len(jobs))) as pool:
        yield from pool.imap_unordered(make_shard, jobs)


def run_ray(jobs: list[ShardJob], config: GenerateConfig) -> Iterator[ShardResult]:
    yield from run_on_ray(jobs, config.workers, config.address)


# An executor yields one result per job, in any order, as the jobs finish.
EXECUTORS: dict[str, Callable[[list[ShardJob], GenerateConfig], Iterator[ShardResult]]] = {
    "local": run_local,
    "ray": run_ray,
}


def _manifest_for(config: GenerateConfig) -> Manifest:
    from afford import __version__

    slots = [name for name, _ in slot_names()]
    return Manifest(
        sequences=config.sequences,
        seed=config.seed,
        shard_size=config.shard_size,
        max_steps=config.max_steps,
        slots=slots,
        splits=default_splits(config.sequences, config.splits_of),
        generator={
            "afford": __version__,
            "layout": asdict(LAYOUTS[config.layout]),
            "layout_name": config.layout,
            "turn_angles": config.turn_angles,
            "actions": config.actions_drawn,
            "images": config.images,
            "masks": config.masks,
        },
    )


def prepare(root: Path, config: GenerateConfig) -> Manifest:
    """Write the manifest of a new dataset, or check that an existing one matches `config`."""
    if config.sequences < 1:
        raise DataError("--sequences must be at least 1")
    if config.turn_angles not in TURN_ANGLES:
        raise DataError(
            f"unknown turn angles {config.turn_angles!r}; expected one of {', '.join(TURN_ANGLES)}"
        )
    if config.actions_drawn not in DRAWS:
        raise DataError(f"unknown action draw {config.actions_drawn!r}; expected one of {', '.join(DRAWS)}")
    if config.masks and not config.images:
        raise DataError("--masks needs images: instance masks are of the state images")
    if config.layout not in LAYOUTS:
        raise DataError(f"unknown layout {config.layout!r}; expected one of {', '.join(LAYOUTS)}")
    if (root / "dataset.json").exists():
        m = read_manifest(root)
        turns = m.generator.get("turn_angles", "quarter")
        drawn = m.generator.get("actions", "uniform")
        layout = m.generator.get("layout_name", "default")
        images = m.generator.get("images", True)
        masks = m.generator.get("masks", False)
        theirs = (m.sequences, m.seed, m.shard_size, m.max_steps, turns, drawn, layout, images, masks)
        ours = (
            config.sequences,
            config.seed,
            config.shard_size,
            config.max_steps,
            config.turn_angles,
            config.actions_drawn,
            config.layout,
            config.images,
            config.masks,
        )
        if theirs != ours:
            raise DataError(
                f"{root}: holds a dataset of {m.sequences} sequences, seed {m.seed}, shard size "
                f"{m.shard_size}, max steps {m.max_steps}, {turns} turns, {drawn} actions, {layout} "
                f"layout, {'with images' if images else 'poses only'}{', masks' if masks else ''}; resume "
                "it with the same settings or use another --out"
            )
        if m.splits != default_splits(config.sequences, config.splits_of):
            raise DataError(
                f"{root}: holds a dataset with the splits {m.splits}; resume it with the --splits-of "
                "it was made with or use another --out"
            )
        return m
    m = _manifest_for(config)
    write_manifest(root, m)
    return m


def generate(root: str | Path, config: GenerateConfig, progress: bool = True) -> GenerateReport:
    """Make every missing shard of the dataset at `root`."""
    from tqdm import tqdm

    root = Path(root)
    manifest = prepare(root, config)
    report = GenerateReport(config.sequences, 0, 0, 0, 0, 0.0)
    _remove_partial_writes(root)
    present, missing = shard_status(root, manifest)
    # Heal: a shard whose checksum fails (a disk error, a copy cut short) is made again.
    for k in tqdm(list(present), desc="check shards", unit="shard", disable=not progress, leave=False):
        problem = check_shard(root, manifest, k)
        if problem is not None:
            report.remade.append(problem)
            shard_path(root, k).unlink(missing_ok=True)
            present.remove(k)
            missing.append(k)
    missing.sort()
    report.skipped_shards = len(present)
    done = sum(len(manifest.shard_range(k)) for k in present)
    jobs = [
        ShardJob(
            str(root),
            k,
            r.start,
            r.stop,
            config.seed,
            config.max_steps,
            config.turn_angles,
            config.actions_drawn,
            config.layout,
            config.images,
            config.masks,
        )
        for k in missing
        for r in [manifest.shard_range(k)]
    ]
    bar = tqdm(
        total=config.sequences,
        initial=done,
        unit="seq",
        disable=not progress,
        desc="generate",
        smoothing=0.05,
    )
    t0 = time.perf_counter()

    def account(result: ShardResult) -> None:
        report.made_shards += 1
        report.executions += result.executions
        report.failed_executions += result.failed
        bar.update(result.sequences)
        bar.set_postfix(exec_per_s=f"{report.executions / max(time.perf_counter() - t0, 1e-9):.1f}")

    if config.executor not in EXECUTORS:
        raise DataError(f"unknown executor {config.executor!r}; expected one of {', '.join(EXECUTORS)}")
    try:
        for result in EXECUTORS[config.executor](jobs, config):
            account(result)
    finally:
        bar.close()
        report.seconds = time.perf_counter() - t0
    _remove_partial_writes(root)  # a worker killed mid-write (its shard was made again by another)
    return report


def _remove_partial_writes(root: Path) -> None:
    """Temporary files of shards being written when their process was killed; only safe while
    no worker of this dataset runs."""
    for stale in (root / SHARD_DIR).glob(".*.tmp") if (root / SHARD_DIR).is_dir() else []:
        stale.unlink(missing_ok=True)
