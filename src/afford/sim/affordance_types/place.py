"""Place: put down what the gripper holds on a support's top or a point along the block."""

from __future__ import annotations

import numpy as np

from afford.sim.affordance_types.base import AffordanceType, register
from afford.sim.constants import BLOCK, MOTION, SUPPORT, TOLERANCES
from afford.sim.geometry import QUARTER_TURNS, rotation, top_point


def find(scene, obj, consider, held_kind) -> None:
    if obj.kind == "support":
        points = [top_point(obj.pos, obj.quat, SUPPORT.half)]
    elif obj.kind == "block" and held_kind != "block":
        points = [top_point(obj.pos, obj.quat, BLOCK.half, dx) for dx in BLOCK.place_offsets]
    else:
        return
    # An upright cup (or a ball) sets down the same at any gripper angle.
    symmetric = held_kind == "ball" or (
        held_kind == "cup" and abs(rotation(scene.held_relpose()[1])[2, 2]) > TOLERANCES.upright_cos
    )
    lift = np.array([0.0, 0.0, tcp_above(scene)])
    for p in points:
        if p is not None:
            consider("place", p, p + lift, QUARTER_TURNS, symmetric)


def tcp_above(scene) -> float:
    """The held object's lowest point comes to rest just above the surface."""
    return scene.held_drop + MOTION.place_clearance


def act(scene, arm, aff, tcp, q_at) -> str:
    scene.release()
    arm.move(q_at, MOTION.t_close, fingers=1.0)
    return ""


def canonical(world, state, aff):
    """The held object (and its riders) rests upright at the point, on the point's host."""
    return world.placed(state, aff)


PLACE = register(
    AffordanceType(
        "place",
        holding=True,
        find=find,
        act=act,
        canonical=canonical,
        tcp_above=tcp_above,
        colour=(30, 200, 255),
        marker=1.5,
    )
)
