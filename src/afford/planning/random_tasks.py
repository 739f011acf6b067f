"""Random planning tasks that nobody tuned by hand (`afford bench random`).

A random scene, 1-4 (or min-max) random affordances executed in it (as in the dataset), and the goal is a
crop of the final image around what changed (positive, RGBD). Success is judged on true
poses: after the plan, every object is within TOLERANCE of where it was in the goal state
(the held object held, fallen objects gone).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from afford.planning.goal import Goal
from afford.planning.tasks import Task, object_names
from afford.sim.affordances import parametrise
from afford.sim.constants import TOLERANCES
from afford.sim.layout import random_layout
from afford.sim.scene import Scene
from afford.sim.specs import SceneError

TOLERANCE = TOLERANCES.position  # metres
CHANGED = 0.05  # a pixel changed when a channel moved by more than this
MARGIN = 4  # pixels around the changed region
MIN_SIZE = 16  # the smallest goal crop, pixels


@dataclass
class PoseGoal:
    """Success predicate: the scene matches the recorded goal state."""

    poses: dict[str, np.ndarray | None]  # position, or None when off the table
    held: str | None

    def holds(self, scene: Scene, see: bool = True) -> bool:
        if scene.held != self.held:
            return False
        for name, want in self.poses.items():
            o = scene.object(name)
            if want is None:
                if o.present:
                    return False
            elif not o.present or (name != self.held and np.linalg.norm(o.pos - want) > TOLERANCE):
                return False
        return True

    def describe(self) -> str:
        return f"every object within {TOLERANCE * 100:.0f} cm of its goal position"


def changed_crop(start: np.ndarray, final: np.ndarray) -> tuple[int, int, int, int]:
    """(row0, row1, col0, col1) around the pixels that differ, padded, at least MIN_SIZE wide."""
    diff = np.abs(final - start).max(-1) > CHANGED
    size = start.shape[0]
    if not diff.any():
        return 0, size, 0, size
    rows, cols = np.nonzero(diff)
    box = []
    for lo, hi in ((rows.min(), rows.max() + 1), (cols.min(), cols.max() + 1)):
        lo, hi = max(0, lo - MARGIN), min(size, hi + MARGIN)
        if hi - lo < MIN_SIZE:
            mid = (lo + hi) // 2
            lo = int(np.clip(mid - MIN_SIZE // 2, 0, size - MIN_SIZE))
            hi = lo + MIN_SIZE
        box += [int(lo), int(hi)]
    return tuple(box)


def random_task(scene: Scene, seed: int, max_steps: int = 4, min_steps: int = 1) -> Task | None:
    """Task `seed`, the state after `min_steps` to `max_steps` random executions: None when
    fewer could be carried out, or they changed nothing visible, or left every object within
    the success tolerance of its start."""
    rng = np.random.default_rng([seed, 7])
    specs = random_layout(rng)
    scene.reset(specs, check=False)  # free of overlaps by construction
    specs = scene.specs()  # settled
    start = scene.observe()
    steps = int(rng.integers(min_steps, max_steps + 1))
    done = 0
    for _ in range(steps):
        candidates = parametrise(scene.affordances())
        while candidates:
            a = candidates.pop(int(rng.integers(len(candidates))))
            snap = scene.snapshot()
            if scene.execute(a).executed:
                done += 1
                break
            scene.restore(snap)
        else:
            break
    final = scene.observe()
    if done == 0 or done < min_steps or not (np.abs(final - start).max(-1) > CHANGED).any():
        return None
    r0, r1, c0, c1 = changed_crop(start, final)
    names = set(object_names(specs))
    poses = {o.name: (o.pos.copy() if o.present else None) for o in scene.objects(present_only=False)}
    poses = {name: pos for name, pos in poses.items() if name in names}
    success = PoseGoal(poses, scene.held)
    try:
        scene.reset(specs)
    except SceneError:
        # Settled where the start checks refuse it (a ball at rest on a lying cup's side, which
        # their rays straight down miss): no task file could hold that start.
        return None
    if success.holds(scene):
        return None  # the executions came back to where they started: nothing to plan
    return Task(
        name=f"random-{seed}",
        challenge=f"reach the state after {done} random affordance executions",
        scene=specs,
        goal=Goal(final[r0:r1, c0:c1], negative=False),
        max_steps=done,
        success=success,
    )
