"""Small geometry of object poses that detection and the affordance types share."""

from __future__ import annotations

import mujoco
import numpy as np

QUARTER_TURNS = (0.0, 90.0, 180.0, 270.0)  # gripper angles tried where any may fit


def wrap180(a):
    """Angle difference into [-180, 180)."""
    return (a + 180.0) % 360.0 - 180.0


def rotation(quat: np.ndarray) -> np.ndarray:
    m = np.zeros(9)
    mujoco.mju_quat2Mat(m, quat)
    return m.reshape(3, 3)


def top_point(pos: np.ndarray, quat: np.ndarray, half: tuple[float, float, float], along_x: float = 0.0):
    """A point on the upward-facing face of a box, `along_x` from its centre along its x axis.

    Returns None when the box stands on its end (its x axis is the one pointing up).
    """
    rot = rotation(quat)
    k = int(np.argmax(np.abs(rot[2, :])))
    if k == 0 and along_x != 0.0:
        return None
    up = np.sign(rot[2, k]) * rot[:, k] * half[k]
    return pos + rot[:, 0] * along_x + up


def axis_yaw(vec: np.ndarray) -> float:
    return float(np.degrees(np.arctan2(vec[1], vec[0])) % 360.0)
