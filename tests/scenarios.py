"""Scripted scenes for the physics tests: each returns a Scene set up for one effect."""

from __future__ import annotations

import numpy as np

from afford.sim.affordances import Affordance
from afford.sim.constants import BLOCK, SUPPORT
from afford.sim.scene import ObjectSpec, Scene

SUPPORT_TOP = 2 * SUPPORT.half[2]
BLOCK_TOP_ON_TABLE = 2 * BLOCK.half[2]
BLOCK_TOP_ON_SUPPORT = SUPPORT_TOP + 2 * BLOCK.half[2]


def find(affs: list[Affordance], kind: str, near, angle: float | None = None) -> Affordance:
    """The affordance of `kind` closest to point `near` (x, y), optionally at `angle`."""
    cands = [
        a for a in affs if a.type == kind and (angle is None or abs((a.angle - angle + 180) % 360 - 180) < 1)
    ]
    if not cands:
        raise AssertionError(f"no {kind} affordance in {affs}")
    return min(cands, key=lambda a: np.hypot(a.position[0] - near[0], a.position[1] - near[1]))


def do(scene: Scene, kind: str, near, angle: float | None = None, turn: int = 0):
    a = find(scene.affordances(), kind, near, angle)
    if turn:
        a = a.with_turn(turn)
    result = scene.execute(a)
    assert result.executed, result.message
    return result


def block_on_support(scene: Scene, support_offset: float, extra: list[ObjectSpec]) -> None:
    """The block (along x, centred at (0, 0.30)) resting on one support `support_offset` along it."""
    scene.reset(
        [
            ObjectSpec.upright("support", support_offset, 0.30),
            ObjectSpec.upright("block", 0.0, 0.30, 0.0, z=SUPPORT_TOP),
            *extra,
        ]
    )
