"""Affordances and the ground-truth detector (paper II.A and III.B).

An affordance of type a exists at a point p (a 3D point plus a gripper angle) if and only if
the robot can *commence* the action there: the gripper state allows it (grasp and turn with an
empty gripper, place while holding), inverse kinematics reaches the commencement pose within
the joint limits, and a gripper-shaped probe (holding a copy of the held object, for place) is
collision-free at that pose. Nothing is said about what executing it will do.
"""

from __future__ import annotations

import mujoco
import numpy as np

from afford.sim.affordance import Affordance, Detection
from afford.sim.affordance_types import REGISTRY, TYPES
from afford.sim.constants import GRIPPER
from afford.sim.mjcf import PROBE_BODIES, park_position

__all__ = ["TYPES", "Affordance", "Detection", "detect", "parametrise", "hand_pose"]


def parametrise(affordances: list[Affordance]) -> list[Affordance]:
    """Fill in execution parameters: each turn becomes +90 and -90 (paper II.D)."""
    out = []
    for a in affordances:
        parameters = REGISTRY[a.type].parameters
        if parameters and a.turn == 0:
            out.extend(a.with_turn(t) for t in parameters)
        else:
            out.append(a)
    return out


def hand_pose(tcp: np.ndarray, yaw_deg: float) -> tuple[np.ndarray, np.ndarray]:
    """Hand (flange) position and quaternion for a downward tool with its TCP at `tcp`."""
    a = np.radians(yaw_deg)
    rot = np.array([[np.cos(a), np.sin(a), 0.0], [np.sin(a), -np.cos(a), 0.0], [0.0, 0.0, -1.0]])
    quat = np.zeros(4)
    mujoco.mju_mat2Quat(quat, rot.flatten())
    return tcp + np.array([0.0, 0.0, GRIPPER.tcp_depth]), quat


class _Checker:
    """Reach (IK) and collision checks against a scratch copy of the scene's state."""

    def __init__(self, scene):
        self.scene = scene
        m = scene.model
        if not hasattr(scene, "_probe_data"):
            scene._probe_data = mujoco.MjData(m)
        self.data = scene._probe_data
        self.data.qpos[:] = scene.data.qpos
        self.probe_bodies = {m.body(b).id for b in PROBE_BODIES.values()}
        self.mocap = {k: m.body_mocapid[m.body(b).id] for k, b in PROBE_BODIES.items()}
        for mid in self.mocap.values():
            self.data.mocap_pos[mid] = park_position(20 + mid) + np.array([0.0, 0.0, 10.0])
        self.ignore = set()
        if scene.held is not None:
            self.ignore.add(scene.body_id(scene.held))
            self.held_kind = scene.kind_of[scene.held]
            self.rel_pos, self.rel_quat = scene.held_relpose()
        self._reach: dict[tuple, bool] = {}
        self._free: dict[tuple, bool] = {}

    def reachable(self, tcp: np.ndarray) -> bool:
        key = tuple(np.round(tcp, 4))
        if key not in self._reach:
            self._reach[key] = self.scene.kin.solve(tcp, 0.0) is not None
        return self._reach[key]

    def free(self, tcp: np.ndarray, yaw_deg: float) -> bool:
        """Is the open gripper (with a copy of what it holds) collision-free at this pose?
        Cached: types that share a commencement pose (grasp and turn the block) probe it once."""
        key = (*np.round(tcp, 4), round(yaw_deg % 360.0, 3))
        if key not in self._free:
            self._free[key] = self._probe(tcp, yaw_deg)
        return self._free[key]

    def _probe(self, tcp: np.ndarray, yaw_deg: float) -> bool:
        d, m = self.data, self.scene.model
        hp, hq = hand_pose(tcp, yaw_deg)
        d.mocap_pos[self.mocap["empty"]] = hp
        d.mocap_quat[self.mocap["empty"]] = hq
        copy = None
        if self.scene.held is not None:
            copy = self.mocap[self.held_kind]
            cp = np.zeros(3)
            mujoco.mju_rotVecQuat(cp, self.rel_pos, hq)
            cq = np.zeros(4)
            mujoco.mju_mulQuat(cq, hq, self.rel_quat)
            d.mocap_pos[copy] = hp + cp
            d.mocap_quat[copy] = cq
        mujoco.mj_kinematics(m, d)
        mujoco.mj_collision(m, d)
        hit = False
        for c in d.contact[: d.ncon]:
            b1, b2 = m.geom_bodyid[c.geom[0]], m.geom_bodyid[c.geom[1]]
            p1, p2 = b1 in self.probe_bodies, b2 in self.probe_bodies
            other = b2 if p1 else b1
            if p1 != p2 and other not in self.ignore and c.dist < 0:
                hit = True
                break
        d.mocap_pos[self.mocap["empty"]] = park_position(30) + np.array([0.0, 0.0, 10.0])
        if copy is not None:
            d.mocap_pos[copy] = park_position(31) + np.array([0.0, 0.0, 10.0])
        return not hit


def detect(scene) -> list[Affordance]:
    """The ground-truth affordance list of the scene's current state (paper III.B): object by
    object, each registered type that the gripper state allows proposes its candidates."""
    check = _Checker(scene)
    found: list[Affordance] = []

    def consider(kind: str, point: np.ndarray, tcp: np.ndarray, angles, symmetric: bool) -> None:
        if not check.reachable(tcp):
            return
        for angle in angles:
            angle = float(angle % 360.0)
            if check.free(tcp, angle):
                found.append(Affordance(kind, tuple(float(v) for v in point), angle, bool(symmetric)))

    holding = scene.held is not None
    held_kind = scene.kind_of[scene.held] if holding else None
    kinds = [k for k in REGISTRY.values() if k.holding == holding]
    for o in scene.objects():
        if not o.held:
            for kind in kinds:
                kind.find(scene, o, consider, held_kind)
    return found
