"""Small random perturbations of object poses at execution (`--perturb`, paper V).

The planner sees the task's start; the world the plan is then executed in differs from it by a
little: every pile of objects (an object on the table with whatever rests on it) is shifted
on the table by a Gaussian offset and turned about the vertical through its base by a
Gaussian angle. A pile moves as one, so what stood balanced still stands; what changes is
where the robot's actions, aimed at the start it saw, land on it. Outcomes that hang on a few
millimetres (a place near a tipping edge) then succeed only sometimes, which is what a
risk-averse planner is for. A draw that would make two piles interpenetrate is refused by the
scene's own checks and drawn again.
"""

from __future__ import annotations

from dataclasses import dataclass

import mujoco
import numpy as np

from afford.errors import UserError
from afford.sim.resting import HOST_HALF, rests_on
from afford.sim.scene import ObjectSpec, Scene, SceneError
from afford.sim.validate import check_numbers

TRIES = 50  # draws before a start is given up as too crowded to perturb
CLIP = 2.0  # offsets beyond this many standard deviations are drawn again


class PerturbError(UserError):
    """No perturbed start was free of overlaps in TRIES draws."""


@dataclass(frozen=True)
class Perturbation:
    position: float = 0.005  # metres: standard deviation of the shift along x and along y
    yaw: float = 3.0  # degrees: standard deviation of the turn about the vertical

    def __post_init__(self):
        if not (self.position >= 0 and self.yaw >= 0):
            raise ValueError(f"perturbation sizes must be >= 0, not {self.position} m and {self.yaw} degrees")

    def draw(self, specs: list[ObjectSpec], base: list[int], rng: np.random.Generator) -> list[ObjectSpec]:
        """Each pile shifted and turned by its own draw; heights and tilts kept. `base[i]`: the
        index of the object at the bottom of object i's pile (i itself for one on the table)."""
        moves = {}
        for b in sorted(set(base)):
            shift = _clipped(rng, 2) * self.position
            moves[b] = (shift, np.radians(_clipped(rng, 1)[0] * self.yaw))
        out = []
        for s, b in zip(specs, base, strict=True):
            (dx, dy), turn = moves[b]
            c, n = np.cos(turn), np.sin(turn)
            ox, oy = specs[b].pos[0], specs[b].pos[1]
            rx, ry = s.pos[0] - ox, s.pos[1] - oy
            pos = (ox + c * rx - n * ry + dx, oy + n * rx + c * ry + dy, s.pos[2])
            quat = np.zeros(4)
            mujoco.mju_mulQuat(
                quat, np.array([np.cos(turn / 2), 0.0, 0.0, np.sin(turn / 2)]), np.asarray(s.quat, float)
            )
            out.append(ObjectSpec(s.kind, tuple(float(v) for v in pos), tuple(float(v) for v in quat)))
        return out


def _clipped(rng: np.random.Generator, n: int) -> np.ndarray:
    x = rng.standard_normal(n)
    while np.any(np.abs(x) > CLIP):
        x = rng.standard_normal(n)
    return x


def piles(scene: Scene, specs: list[ObjectSpec]) -> list[int]:
    """For each object of `specs`, the index of the object at the bottom of its pile, read
    from the settled start (what rests on a support or the block)."""

    scene.reset(specs)
    names = check_numbers(specs)
    host = {}
    for i, name in enumerate(names):
        for j, other in enumerate(names):
            if j != i and specs[j].kind in HOST_HALF and rests_on(scene, name, other):
                host[i] = j
                break
    base = []
    for i in range(len(specs)):
        b, seen = i, {i}
        while b in host and host[b] not in seen:
            b = host[b]
            seen.add(b)
        base.append(b)
    return base


def reset_perturbed(
    scene: Scene,
    specs: list[ObjectSpec],
    perturbation: Perturbation,
    rng: np.random.Generator,
    base: list[int] | None = None,
) -> list[ObjectSpec]:
    """Reset `scene` to a perturbed copy of `specs` (settled); returns the copy used. `base`:
    `piles(scene, specs)` when the caller has it (reading it resets the scene once more)."""
    if base is None:
        base = piles(scene, specs)
    for _ in range(TRIES):
        drawn = perturbation.draw(specs, base, rng)
        try:
            scene.reset(drawn)
            return drawn
        except SceneError:
            continue
    raise PerturbError(f"no perturbed start free of overlaps in {TRIES} draws: lower --perturb")
