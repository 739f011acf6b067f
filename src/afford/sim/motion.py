"""Carrying out an affordance with the arm (paper III.A): IK waypoints, smooth joint-space
moves of the kinematic arm, a weld for the grasp, then back to the default pose and settle.

Execution reads only the affordance (type, position, angle, turn), never an object id, so an
affordance recognised by a net is executed exactly like a ground-truth one. A grasp holds
whatever object centre lies within `MOTION.grasp_radius` of the TCP when the fingers close.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from afford.sim.affordances import Affordance
from afford.sim.constants import BALL, BLOCK, CUP, GRASPABLE, GRIPPER, MOTION, PHYSICS

GRIP_HALF_WIDTH = {"cup": CUP.radius, "ball": BALL.radius, "block": BLOCK.half[1]}


@dataclass
class ExecutionResult:
    """What happened: whether the arm could carry the affordance out, and what it holds now."""

    affordance: Affordance
    executed: bool
    held: str | None
    steps: int
    message: str = ""


class _Arm:
    """Moves the scene's kinematic arm along smooth joint-space segments."""

    def __init__(self, scene):
        self.scene = scene
        self.fingers = 1.0

    @property
    def q(self) -> np.ndarray:
        return self.scene.data.qpos[self.scene.arm_qadr].copy()

    def move(self, q_to: np.ndarray, duration: float, fingers: float | None = None) -> None:
        s = self.scene
        q_from = self.q
        q_to = q_to.copy()
        # Joint 6 is unlimited in effect: take the short way round to the same hand angle.
        q_to[5] = q_from[5] + (q_to[5] - q_from[5] + np.pi) % (2 * np.pi) - np.pi
        f_from = self.fingers
        f_to = self.fingers if fingers is None else fingers
        n = max(1, round(duration / PHYSICS.timestep))
        for i in range(1, n + 1):
            t = i / n
            u = t * t * (3 - 2 * t)  # smoothstep: zero velocity at both ends
            du = 6 * t * (1 - t) / (n * PHYSICS.timestep)
            s.set_arm(q_from + u * (q_to - q_from), f_from + u * (f_to - f_from), dq=du * (q_to - q_from))
            s.step()
        self.fingers = f_to

    def line(self, tcp_to: np.ndarray, yaw: float, duration: float, waypoints: int = 6) -> bool:
        """Move the TCP along a straight line (an approach or a lift) through IK waypoints.

        Joint-space interpolation between two distant poses can swing the TCP sideways near
        the table, dragging a held object through its neighbours; a chain of nearby IK
        solutions keeps the path straight. Returns False (without moving) if a waypoint is
        out of reach.
        """
        s = self.scene
        tcp_from = s.data.site_xpos[s.model.site("tcp").id].copy()
        qs = [self.q]
        for k in range(1, waypoints + 1):
            q = s.kin.solve(tcp_from + (tcp_to - tcp_from) * k / waypoints, yaw, seed=qs[-1])
            if q is None:
                return False
            q[5] = qs[-1][5] + (q[5] - qs[-1][5] + np.pi) % (2 * np.pi) - np.pi
            qs.append(q)
        path = np.array(qs)
        n = max(1, round(duration / PHYSICS.timestep))
        for i in range(1, n + 1):
            t = i / n
            u = t * t * (3 - 2 * t) * waypoints
            du = 6 * t * (1 - t) * waypoints / (n * PHYSICS.timestep)
            k = min(int(u), waypoints - 1)
            seg = path[k + 1] - path[k]
            s.set_arm(path[k] + (u - k) * seg, self.fingers, dq=du * seg)
            s.step()
        return True


def _nearest_graspable(scene, tcp: np.ndarray) -> str | None:
    best, best_d = None, MOTION.grasp_radius
    for o in scene.objects():
        if o.kind in GRASPABLE and not o.held:
            d = float(np.linalg.norm(o.pos - tcp))
            if d < best_d:
                best, best_d = o.name, d
    return best


def _finger_fraction(kind: str) -> float:
    return (GRIP_HALF_WIDTH[kind] + GRIPPER.finger_half[0]) / GRIPPER.open_half_width


def execute(scene, aff: Affordance) -> ExecutionResult:
    """Carry out `aff` in `scene`; the scene ends settled with the arm at its default pose."""
    start = scene.steps
    if aff.type in ("grasp", "turn") and scene.held is not None:
        return ExecutionResult(aff, False, scene.held, 0, f"cannot {aff.type} while holding {scene.held}")
    if aff.type == "place" and scene.held is None:
        return ExecutionResult(aff, False, None, 0, "cannot place with an empty gripper")
    if aff.type == "turn" and aff.turn == 0:
        raise ValueError("a turn affordance needs its parameter: use aff.with_turn(+90 or -90)")

    target = np.asarray(aff.position, dtype=float)
    tcp = target.copy()
    if aff.type == "place":
        tcp[2] += scene.held_drop + MOTION.place_clearance
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

    arm = _Arm(scene)
    if scene.held is not None:
        arm.fingers = _finger_fraction(scene.kind_of[scene.held])
    arm.move(q_high, MOTION.t_travel)
    if not arm.line(tcp, aff.angle, MOTION.t_approach):
        arm.move(q_at, MOTION.t_approach)
    message = ""
    if aff.type == "place":
        scene.release()
        arm.move(q_at, MOTION.t_close, fingers=1.0)
    else:
        name = _nearest_graspable(scene, tcp)
        if name is None:
            arm.move(q_at, MOTION.t_close, fingers=0.0)
            message = "nothing to grasp there"
        else:
            scene.attach(name)
            arm.move(q_at, MOTION.t_close, fingers=_finger_fraction(scene.kind_of[name]))
        if aff.type == "turn" and name is not None:
            lift = tcp + np.array([0.0, 0.0, MOTION.turn_lift])
            q_lift = scene.kin.solve(lift, aff.angle, seed=q_at)
            if q_lift is not None:
                # +90 turns counter-clockwise seen from above; with the tool pointing down
                # that is a negative turn of joint 6 about its own (downward) axis.
                turn = -np.radians(aff.turn)
                q_turned, q_down = q_lift.copy(), q_at.copy()
                q_turned[5] += turn
                q_down[5] = q_turned[5]
                arm.move(q_lift, MOTION.t_close)
                arm.move(q_turned, MOTION.t_turn)
                arm.move(q_down, MOTION.t_close)
            scene.release()
            arm.move(arm.q, MOTION.t_close, fingers=1.0)
    up = scene.data.site_xpos[scene.model.site("tcp").id].copy()
    up[2] = high[2]
    yaw_now = scene.kin.yaw_of(scene.data.site_xmat[scene.model.site("tcp").id].reshape(3, 3))
    if not arm.line(up, yaw_now, MOTION.t_approach):
        arm.move(q_high, MOTION.t_approach)
    # Home with the fingers at one opening for each gripper state (open when empty, whatever
    # a failed grasp left them at), and the joints exactly at home: joint 6 took the short
    # way round, which may differ from home by whole turns.
    fingers_home = 1.0 if scene.held is None else _finger_fraction(scene.kind_of[scene.held])
    arm.move(scene.home_q, MOTION.t_travel, fingers=fingers_home)
    scene.set_arm(scene.home_q, fingers_home)
    if scene.held is not None:
        scene.carry_held()
    scene.settle()
    return ExecutionResult(aff, True, scene.held, scene.steps - start, message)
