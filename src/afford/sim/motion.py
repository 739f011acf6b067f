"""Carrying out an affordance with the arm (paper III.A): IK waypoints, smooth joint-space
moves of the kinematic arm, a weld for the grasp, then back to the default pose and settle.

Execution reads only the affordance (type, position, angle, turn), never an object id, so an
affordance recognised by a net is executed exactly like a ground-truth one. A grasp holds
whatever object centre lies within `MOTION.grasp_radius` of the TCP when the fingers close.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from afford.sim.affordance_types import REGISTRY
from afford.sim.affordances import Affordance
from afford.sim.arm import Arm, finger_fraction
from afford.sim.arm_path import key_points
from afford.sim.constants import MOTION


@dataclass
class ExecutionResult:
    """What happened: whether the arm could carry the affordance out, and what it holds now."""

    affordance: Affordance
    executed: bool
    held: str | None
    steps: int
    message: str = ""


def execute(scene, aff: Affordance) -> ExecutionResult:
    """Carry out `aff` in `scene`; the scene ends settled with the arm at its default pose.

    Common to every type: the gripper state it needs, the approach from above to the
    commencement pose, and the return home; what happens there is the type's `act`."""
    kind = REGISTRY[aff.type]
    start = scene.steps
    if kind.holding and scene.held is None:
        return ExecutionResult(aff, False, None, 0, f"cannot {aff.type} with an empty gripper")
    if not kind.holding and scene.held is not None:
        return ExecutionResult(aff, False, scene.held, 0, f"cannot {aff.type} while holding {scene.held}")
    if kind.parameters and aff.turn == 0:
        raise ValueError(f"a {aff.type} affordance needs its parameter: use aff.with_turn({kind.parameters})")

    target = np.asarray(aff.position, dtype=float)
    tcp = target.copy()
    if kind.tcp_above is not None:
        tcp[2] += kind.tcp_above(scene)
    q_high = q_at = None
    # Approach from as high as the arm reaches above the target (far targets allow less).
    for z in (max(MOTION.carry_height, tcp[2] + MOTION.hover), tcp[2] + MOTION.hover, tcp[2] + 0.04):
        high = np.array([tcp[0], tcp[1], z])
        q_high = scene.kin.solve(high, aff.angle)
        if q_high is not None:
            q_at = scene.kin.solve(tcp, aff.angle, seed=q_high)
            break
    if q_at is None:
        return ExecutionResult(aff, False, scene.held, 0, "out of reach")

    arm = Arm(scene)
    scene.tcp_trace = []
    if scene.held is not None:
        arm.fingers = finger_fraction(scene.kind_of[scene.held])
    arm.move(q_high, MOTION.t_travel)
    if not arm.line(tcp, aff.angle, MOTION.t_approach):
        arm.move(q_at, MOTION.t_approach)
    message = kind.act(scene, arm, aff, tcp, q_at)
    up = scene.data.site_xpos[scene.model.site("tcp").id].copy()
    up[2] = high[2]
    yaw_now = scene.kin.yaw_of(scene.data.site_xmat[scene.model.site("tcp").id].reshape(3, 3))
    if not arm.line(up, yaw_now, MOTION.t_approach):
        arm.move(q_high, MOTION.t_approach)
    # Home with the fingers at one opening for each gripper state (open when empty, whatever
    # a failed grasp left them at), and the joints exactly at home: joint 6 took the short
    # way round, which may differ from home by whole turns.
    fingers_home = 1.0 if scene.held is None else finger_fraction(scene.kind_of[scene.held])
    arm.move(scene.home_q, MOTION.t_travel, fingers=fingers_home)
    scene.set_arm(scene.home_q, fingers_home)
    if scene.held is not None:
        scene.carry_held()
    scene.last_path = key_points(scene.tcp_trace)
    scene.tcp_trace = None
    scene.settle()
    return ExecutionResult(aff, True, scene.held, scene.steps - start, message)
