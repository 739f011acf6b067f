"""Turn: grasp the block, lift it a little, turn it by +90 or -90 degrees about the vertical,
set it down and let go (paper II.A; the parameter is filled in by the planner, II.D)."""

from __future__ import annotations

import numpy as np

from afford.sim.affordance_types.base import AffordanceType, register
from afford.sim.affordance_types.grasp import act as grasp_act
from afford.sim.affordance_types.grasp import block_angle
from afford.sim.constants import MOTION

TURN_PARAMETERS = (90, -90)


def find(scene, obj, consider, held_kind) -> None:
    # Wherever the block can be grasped it can be turned: the same commencement pose.
    if obj.kind == "block":
        consider("turn", obj.pos, obj.pos, [block_angle(obj)], False)


def act(scene, arm, aff, tcp, q_at) -> str:
    message = grasp_act(scene, arm, aff, tcp, q_at)
    if message:
        return message
    lift = tcp + np.array([0.0, 0.0, MOTION.turn_lift])
    q_lift = scene.kin.solve(lift, aff.angle, seed=q_at)
    if q_lift is not None:
        # +90 turns counter-clockwise seen from above; with the tool pointing down that is a
        # negative turn of joint 6 about its own (downward) axis.
        turn = -np.radians(aff.turn)
        q_turned, q_down = q_lift.copy(), q_at.copy()
        q_turned[5] += turn
        q_down[5] = q_turned[5]
        arm.move(q_lift, MOTION.t_close)
        arm.move(q_turned, MOTION.t_turn)
        arm.move(q_down, MOTION.t_close)
    scene.release()
    arm.move(arm.q, MOTION.t_close, fingers=1.0)
    return ""


def canonical(world, state, aff):
    """The block turns about its centre, with whatever rests on it."""
    target = world.object_at(state, np.asarray(aff.position))
    if target is None:
        return None
    return world.turned(state, target, aff.turn)


TURN = register(
    AffordanceType(
        "turn",
        holding=False,
        find=find,
        act=act,
        canonical=canonical,
        parameters=TURN_PARAMETERS,
        colour=(255, 40, 220),
    )
)
