"""Grasp: close the gripper on a cup, a ball or the block (paper II.A)."""

from __future__ import annotations

import numpy as np

from afford.sim.affordance_types.base import AffordanceType, register
from afford.sim.arm import finger_fraction, nearest_graspable
from afford.sim.constants import MOTION, TOLERANCES
from afford.sim.geometry import QUARTER_TURNS, axis_yaw, rotation


def block_angle(obj) -> float:
    """The fingers close across the block's width: the angle follows its long axis."""
    return (axis_yaw(rotation(obj.quat)[:, 0]) + 90.0) % 180.0


def find(scene, obj, consider, held_kind) -> None:
    if obj.kind in ("cup", "ball"):
        axis = obj.up_axis
        upright = obj.kind == "ball" or abs(axis[2]) > TOLERANCES.upright_cos
        base = 0.0 if upright else axis_yaw(axis)
        consider("grasp", obj.pos, obj.pos, [base + q for q in QUARTER_TURNS], upright)
    elif obj.kind == "block":
        consider("grasp", obj.pos, obj.pos, [block_angle(obj)], False)


def act(scene, arm, aff, tcp, q_at) -> str:
    """Close on whatever object centre lies within reach of the TCP; the weld holds it."""
    name = nearest_graspable(scene, tcp)
    if name is None:
        arm.move(q_at, MOTION.t_close, fingers=0.0)
        return "nothing to grasp there"
    scene.attach(name)
    arm.move(q_at, MOTION.t_close, fingers=finger_fraction(scene.kind_of[name]))
    return ""


def canonical(world, state, aff):
    """The object at the point is held, with whatever rests on it."""
    target = world.object_at(state, np.asarray(aff.position))
    if target is None:
        return None
    return world.held(state, target, aff)


GRASP = register(
    AffordanceType("grasp", holding=False, find=find, act=act, canonical=canonical, colour=(40, 220, 60))
)
