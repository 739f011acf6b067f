"""Inverse kinematics of the UR3-like arm: damped least squares on MuJoCo Jacobians.

A tool pose here is a TCP position, a tool axis pointing straight down (working) or up (the
default pose), and a gripper yaw: the direction in the table plane along which the fingers
open. Joint 6 turns the hand about the tool axis, and with the axis vertical that is a turn
about the vertical through the TCP. So we solve position and axis with joints 1-6, then set
the yaw exactly with q6 alone; this is also how a turn affordance rotates the block.
"""

from __future__ import annotations

from dataclasses import dataclass

import mujoco
import numpy as np

from afford.sim.constants import UR3_DH
from afford.sim.mjcf import ARM_JOINTS

# A working posture (elbow up, tool down over the work area) that seeds every solve, so the
# same target always gives the same joint solution.
READY_SEED = np.array([-np.pi / 2, -1.3, 1.9, -2.2, -np.pi / 2, 0.0])
HOME_SEED = np.array([np.pi / 2, -1.2, 0.9, -0.9, 1.57, 0.0])


def _cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    # np.cross's argument handling costs more than the product itself in this hot loop.
    return np.array([a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]])


@dataclass(frozen=True)
class IKConfig:
    max_iterations: int = 120
    damping: float = 0.02
    pos_tolerance: float = 5e-4  # metres
    axis_tolerance: float = 2e-3  # radians
    max_step: float = 0.3  # radians per iteration, keeps DLS from jumping branches


class ArmKinematics:
    """Forward and inverse kinematics on a private MjData, never touching the simulation's."""

    def __init__(self, model: mujoco.MjModel, config: IKConfig = IKConfig()):
        self.model = model
        self.config = config
        self._data = mujoco.MjData(model)
        self.qpos_adr = np.array([model.joint(j).qposadr[0] for j in ARM_JOINTS])
        self.dof_adr = np.array([model.joint(j).dofadr[0] for j in ARM_JOINTS])
        self.site = model.site("tcp").id
        self._jacp = np.zeros((3, model.nv))
        self._jacr = np.zeros((3, model.nv))

    def forward(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """TCP position (3,) and rotation matrix (3, 3) for arm joints q."""
        d = self._data
        d.qpos[self.qpos_adr] = q
        mujoco.mj_kinematics(self.model, d)
        return d.site_xpos[self.site].copy(), d.site_xmat[self.site].reshape(3, 3).copy()

    def yaw_of(self, rot: np.ndarray) -> float:
        """Gripper yaw in degrees [0, 360): the finger-opening axis (hand x) in the table plane."""
        x = rot[:, 0]
        return float(np.degrees(np.arctan2(x[1], x[0])) % 360.0)

    def solve(
        self,
        pos: np.ndarray,
        yaw_deg: float,
        down: bool = True,
        seed: np.ndarray | None = None,
    ) -> np.ndarray | None:
        """Joints that put the TCP at `pos`, tool axis down (or up), fingers along `yaw_deg`.

        Returns None when no solution within the joint limits is found (out of reach).
        """
        cfg = self.config
        lim = UR3_DH.joint_limit
        q = np.array(READY_SEED if seed is None else seed, dtype=float)
        target_axis = np.array([0.0, 0.0, -1.0 if down else 1.0])
        d = self._data
        converged = False
        for _ in range(cfg.max_iterations):
            d.qpos[self.qpos_adr] = q
            mujoco.mj_kinematics(self.model, d)
            mujoco.mj_comPos(self.model, d)
            p = d.site_xpos[self.site]
            axis = d.site_xmat[self.site].reshape(3, 3)[:, 2]
            e_pos = pos - p
            e_rot = _cross(axis, target_axis)
            if axis @ target_axis < 0:  # more than 90 degrees away: the cross product shrinks
                e_rot = e_rot / max(np.linalg.norm(e_rot), 1e-6)
            if np.linalg.norm(e_pos) < cfg.pos_tolerance and np.linalg.norm(e_rot) < cfg.axis_tolerance:
                converged = axis @ target_axis > 0
                break
            mujoco.mj_jacSite(self.model, d, self._jacp, self._jacr, self.site)
            jac = np.vstack([self._jacp[:, self.dof_adr], self._jacr[:, self.dof_adr]])
            err = np.concatenate([e_pos, e_rot])
            dq = jac.T @ np.linalg.solve(jac @ jac.T + cfg.damping**2 * np.eye(6), err)
            step = np.max(np.abs(dq))
            if step > cfg.max_step:
                dq *= cfg.max_step / step
            q = np.clip(q + dq, -lim, lim)
        if not converged:
            return None
        # Yaw: q6 turns the hand about the (vertical) tool axis; with the axis pointing down a
        # positive q6 turns the fingers clockwise seen from above, hence the sign.
        _, rot = self.forward(q)
        delta = np.radians((yaw_deg - self.yaw_of(rot) + 180.0) % 360.0 - 180.0)
        q[5] += delta if rot[2, 2] > 0 else -delta
        q[5] = (q[5] + np.pi) % (2 * np.pi) - np.pi
        return q

    def home(self, tcp: np.ndarray) -> np.ndarray:
        """The default pose: TCP at `tcp`, gripper pointing up (paper III.A)."""
        q = self.solve(np.asarray(tcp, dtype=float), 0.0, down=False, seed=HOME_SEED)
        if q is None:
            raise RuntimeError(f"the default pose {tcp} is out of the arm's reach")
        return q
