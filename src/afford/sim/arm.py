"""The kinematic arm's moves, and what the gripper closes on: shared by the affordance types."""

from __future__ import annotations

import numpy as np

from afford.sim.constants import BALL, BLOCK, CUP, GRASPABLE, GRIPPER, MOTION, PHYSICS

GRIP_HALF_WIDTH = {"cup": CUP.radius, "ball": BALL.radius, "block": BLOCK.half[1]}


class Arm:
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
            s.record_tcp()
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
            s.record_tcp()
        return True


def nearest_graspable(scene, tcp: np.ndarray) -> str | None:
    best, best_d = None, MOTION.grasp_radius
    for o in scene.objects():
        if o.kind in GRASPABLE and not o.held:
            d = float(np.linalg.norm(o.pos - tcp))
            if d < best_d:
                best, best_d = o.name, d
    return best


def finger_fraction(kind: str) -> float:
    return (GRIP_HALF_WIDTH[kind] + GRIPPER.finger_half[0]) / GRIPPER.open_half_width
