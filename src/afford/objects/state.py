"""Object states as the dynamics nets see them, and back to poses.

A state is one row per object slot (`sim/mjcf.slot_names`: 3 cups, 3 balls, 2 supports, 1
block), read from the datasets' pose rows (x, y, z, qw, qx, qy, qz; NaN: not on the table).
An object's orientation is given by two of its axes in the world: `up` (its own z: a cup's
opening) and `along` (its own x: the block's length); both are smooth where a quaternion is
not (q and -q are one pose), and a net's prediction of them turns back into a quaternion by
Gram-Schmidt.
"""

from __future__ import annotations

import numpy as np

from afford.sim.constants import TABLE, TOLERANCES
from afford.sim.mjcf import slot_names

SLOTS = tuple(slot_names())
KINDS = ("cup", "ball", "support", "block")
SLOT_KIND = np.array([KINDS.index(kind) for _, kind in SLOTS])
N_SLOTS = len(SLOTS)
# Positions enter the nets in decimetres from the table's centre: order one across the table.
POS_SCALE = 10.0
CENTRE = np.array([TABLE.centre[0], TABLE.centre[1], 0.0])
# present, held, kind one-hot, position, up axis, along axis
FEATURES = 2 + len(KINDS) + 3 + 3 + 3


def quat_axes(quat: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(..., 4) quaternions (w, x, y, z) -> the body's z axis and x axis in the world, (..., 3) each."""
    w, x, y, z = np.moveaxis(quat, -1, 0)
    up = np.stack([2 * (x * z + w * y), 2 * (y * z - w * x), 1 - 2 * (x * x + y * y)], axis=-1)
    along = np.stack([1 - 2 * (y * y + z * z), 2 * (x * y + w * z), 2 * (x * z - w * y)], axis=-1)
    return up, along


def axes_quat(up: np.ndarray, along: np.ndarray) -> np.ndarray:
    """The quaternion whose z axis is `up` and whose x axis is `along` made orthogonal to it."""
    z = up / np.maximum(np.linalg.norm(up, axis=-1, keepdims=True), 1e-9)
    x = along - (along * z).sum(-1, keepdims=True) * z
    bad = np.linalg.norm(x, axis=-1) < 1e-6  # along parallel to up: any x across it serves
    if np.any(bad):
        other = np.where(np.abs(z[..., :1]) < 0.9, [1.0, 0.0, 0.0], [0.0, 1.0, 0.0])
        alt = other - (other * z).sum(-1, keepdims=True) * z
        x = np.where(bad[..., None], alt, x)
    x = x / np.linalg.norm(x, axis=-1, keepdims=True)
    y = np.cross(z, x)
    m = np.stack([x, y, z], axis=-1)  # columns are the body's axes
    return _matrix_quat(m)


def _matrix_quat(m: np.ndarray) -> np.ndarray:
    """(..., 3, 3) rotation matrices -> (..., 4) unit quaternions, w >= 0."""
    shape = m.shape[:-2]
    m = m.reshape(-1, 3, 3)
    q = np.zeros((len(m), 4))
    for i, r in enumerate(m):  # Shepperd's method: take the largest of the four squares
        t = np.trace(r)
        if t > 0:
            s = 2 * np.sqrt(1 + t)
            q[i] = (s / 4, (r[2, 1] - r[1, 2]) / s, (r[0, 2] - r[2, 0]) / s, (r[1, 0] - r[0, 1]) / s)
        else:
            k = int(np.argmax(np.diag(r)))
            a, b = (k + 1) % 3, (k + 2) % 3
            s = 2 * np.sqrt(1 + r[k, k] - r[a, a] - r[b, b])
            v = np.zeros(3)
            v[k] = s / 4
            v[a] = (r[a, k] + r[k, a]) / s
            v[b] = (r[b, k] + r[k, b]) / s
            q[i] = ((r[b, a] - r[a, b]) / s, *v)
    q *= np.where(q[:, :1] < 0, -1.0, 1.0)
    return q.reshape(*shape, 4)


def slot_features(poses: np.ndarray, held: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Pose rows (..., slots, 7) and held slots (...) -> features (..., slots, FEATURES) float32
    and the present mask (..., slots) bool. An object not on the table has all-zero features."""
    present = ~np.isnan(poses[..., 0])
    p = np.where(present[..., None], poses, 0.0)
    up, along = quat_axes(np.where(present[..., None], p[..., 3:7], [1.0, 0.0, 0.0, 0.0]))
    is_held = np.arange(N_SLOTS) == np.asarray(held)[..., None]
    kinds = np.broadcast_to(np.eye(len(KINDS))[SLOT_KIND], (*poses.shape[:-1], len(KINDS)))
    f = np.concatenate(
        [present[..., None], is_held[..., None], kinds, (p[..., :3] - CENTRE) * POS_SCALE, up, along], axis=-1
    )
    return (f * present[..., None]).astype(np.float32), present


def moved(before: np.ndarray, after: np.ndarray) -> np.ndarray:
    """(..., slots) bool: the objects whose pose rows differ (one appearing or going counts).
    The dynamics copy a still object's row exactly, so equality is the test."""
    same = (before == after) | (np.isnan(before) & np.isnan(after))
    return ~same.all(-1)


def uprightness(poses: np.ndarray) -> np.ndarray:
    """(..., slots) the z component of each object's up axis: 1 upright, 0 lying, -1 upside down."""
    up, _ = quat_axes(np.nan_to_num(poses[..., 3:7]))
    return up[..., 2]


# How an object stands, from its up axis: what a person would say of a cup seen from above.
POSTURES = ("upright", "tipped", "lying")
LYING_COS = 0.42  # an axis more than 65 degrees off vertical: lying on its side


def posture(up_z: float) -> str:
    """upright (axis within 25 degrees of vertical), lying (more than 65 off), else tipped;
    upside down counts as tipped."""
    if up_z >= TOLERANCES.upright_cos:
        return "upright"
    if abs(up_z) <= LYING_COS:
        return "lying"
    return "tipped"


# Where an up axis is put when the perception net's posture class disagrees with it: the
# middle of that posture's band of angles from vertical.
POSTURE_COS = {"upright": 1.0, "tipped": float(np.cos(np.radians(45))), "lying": 0.0}


def fit_posture(up: np.ndarray, name: str) -> np.ndarray:
    """A unit up axis made to agree with posture `name`: unchanged if it already does, else
    tilted to the middle of that posture's band, keeping its horizontal direction (and its
    sign, so an upside-down tipped axis stays below the horizon)."""
    up = up / max(float(np.linalg.norm(up)), 1e-9)
    if posture(float(up[2])) == name:
        return up
    flat = np.array([up[0], up[1], 0.0])
    if np.linalg.norm(flat) < 1e-6:  # no horizontal direction to keep: any serves
        flat = np.array([1.0, 0.0, 0.0])
    flat /= np.linalg.norm(flat)
    c = POSTURE_COS[name]
    sign = -1.0 if up[2] < 0 and name == "tipped" else 1.0
    return flat * np.sqrt(1 - c * c) + np.array([0.0, 0.0, sign * c])
