"""One shard of a dataset: its sequences made in one simulator and written in one file.

The unit of work that every executor hands out (`generate.py`'s local pool, `ray_executor.py`'s
Ray tasks). Sequence i draws everything from its own generator seeded by (seed, i), and the
simulator is reset before it, so a shard's bytes depend only on its job, never on the worker.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from afford.data.draws import DRAWS, pose_array
from afford.data.format import Sequence, quantise, shard_path, write_shard
from afford.sim.affordance import AFF_WIDTH, encode_affordance
from afford.sim.affordances import parametrise
from afford.sim.arm_path import PATH_POINTS, PATH_WIDTH
from afford.sim.layout import LAYOUTS, random_layout
from afford.sim.scene import Scene

TURN_ANGLES = ("quarter", "continuous")


def make_sequence(
    scene: Scene,
    seed: int,
    index: int,
    max_steps: int,
    turn_angles: str = "quarter",
    actions_drawn: str = "uniform",
    layout: str = "default",
    images: bool = True,
    masks: bool = False,
) -> tuple[Sequence, int]:
    """Sequence `index` of the dataset with `seed`, and how many drawn executions failed;
    `actions_drawn`: a key of draws.DRAWS; `layout`: a key of layout.LAYOUTS. Without `images`
    nothing is rendered and the images have size 0: rendering reads the simulator and never
    changes it, so the poses are those of the same sequence with images. With `masks`, each state
    also keeps the slot seen at each pixel (`Scene.instance_mask`)."""
    draw = DRAWS[actions_drawn]
    rng = np.random.default_rng([seed, index])
    arrangement = LAYOUTS[layout]
    for _ in range(arrangement.tries if arrangement.level_start else 1):
        scene.reset(random_layout(rng, arrangement), check=False)  # free of overlaps by construction
        if not arrangement.level_start or _block_level(scene, arrangement.level_cos):
            break
    slots = tuple(name for name, _ in scene.slots)
    rgbs, depths, lists, actions, held, poses, paths, seen = [], [], [], [], [], [], [], []
    no_rgb, no_depth = np.zeros((0, 0, 3), np.uint8), np.zeros((0, 0), np.uint16)
    failed = 0
    for step in range(max_steps + 1):
        rgb, depth = quantise(scene.observe()) if images else (no_rgb, no_depth)
        affs = scene.affordances()
        if masks:
            seen.append(scene.instance_mask())
        rgbs.append(rgb)
        depths.append(depth)
        lists.append(np.array([encode_affordance(a) for a in affs], dtype=np.float32).reshape(-1, AFF_WIDTH))
        held.append(slots.index(scene.held) if scene.held else -1)
        poses.append(pose_array(scene))
        if step == max_steps:
            break
        # Draw from the list with turn parameters filled in (paper II.D).
        candidates = parametrise(affs)
        if turn_angles == "continuous":
            # Each +-90 becomes an angle of its sign and a random size: still one each way.
            candidates = [
                a.with_turn(float(np.sign(a.turn) * rng.uniform(1.0, 180.0))) if a.turn else a
                for a in candidates
            ]
        executed, f = draw(scene, candidates, rng)
        failed += f
        if executed is None:
            break
        actions.append(encode_affordance(executed))
        paths.append(scene.last_path)
    seq = Sequence(
        index=index,
        rgb=np.stack(rgbs),
        depth=np.stack(depths),
        affordances=lists,
        actions=np.array(actions, dtype=np.float32).reshape(-1, AFF_WIDTH),
        held=np.array(held, dtype=np.int8),
        poses=np.stack(poses),
        slots=slots,
        arm_paths=np.array(paths, dtype=np.float32).reshape(-1, PATH_POINTS, PATH_WIDTH),
        masks=np.stack(seen) if masks else None,
    )
    return seq, failed


def _block_level(scene: Scene, cos: float) -> bool:
    """Whether the scene's block (if any) rests level, its up axis within `cos` of vertical."""
    blocks = [o for o in scene.objects() if o.kind == "block"]
    return all(o.up_axis[2] >= cos for o in blocks)


@dataclass(frozen=True)
class ShardJob:
    root: str  # the dataset folder, as the worker sees it (shared storage on a cluster)
    shard: int
    start: int  # first sequence index
    stop: int
    seed: int
    max_steps: int
    turn_angles: str = "quarter"
    actions_drawn: str = "uniform"
    layout: str = "default"
    images: bool = True
    masks: bool = False


@dataclass(frozen=True)
class ShardResult:
    shard: int
    sequences: int
    executions: int
    failed: int


_worker_scene: Scene | None = None  # one simulator per worker process, made on its first shard


def make_shard(job: ShardJob) -> ShardResult:
    """Make and write one shard; writing it again gives the same bytes, so a retried job is harmless."""
    global _worker_scene
    if _worker_scene is None:
        _worker_scene = Scene()
    seqs, failed = [], 0
    for i in range(job.start, job.stop):
        seq, f = make_sequence(
            _worker_scene,
            job.seed,
            i,
            job.max_steps,
            job.turn_angles,
            job.actions_drawn,
            job.layout,
            job.images,
            job.masks,
        )
        seqs.append(seq)
        failed += f
    write_shard(shard_path(Path(job.root), job.shard), seqs)
    return ShardResult(job.shard, len(seqs), sum(s.length for s in seqs), failed)
