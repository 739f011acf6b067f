"""Training-time augmentation (paper II.B, II.C and III.C).

Everything acts on the stored form: (T, H, W, 4) RGBD images and affordance rows in the world
frame (format.AFF_COLUMNS). A geometric change to the image is carried over to the rows through
the camera model, so the rows stay true world coordinates of what the new image shows.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from afford.sim import camera
from afford.sim.affordance import Col as C
from afford.sim.constants import CAMERA


@dataclass(frozen=True)
class AugmentConfig:
    shift_px: int = 4  # translation by up to this many pixels each way
    mirror: bool = True  # left-right mirror, half the time
    angle_flip: bool = True  # +180 degrees, half the time, where the angle does not matter
    position_noise: float = 0.0  # metres (std) added to executed actions' positions
    angle_noise: float = 0.0  # degrees (std) added to executed actions' angles


NO_AUGMENT = AugmentConfig(shift_px=0, mirror=False, angle_flip=False)


def _z_to_unit_depth(z: np.ndarray) -> np.ndarray:
    return camera.depth_to_unit(CAMERA.pos[2] - z)


def _move_rows(rows: np.ndarray, dcol: int, drow: int, mirror: bool) -> np.ndarray:
    """Rows whose positions follow an image shift by (dcol, drow) pixels and an optional mirror."""
    if len(rows) == 0:
        return rows
    out = rows.copy()
    px = camera.world_to_pixel(rows[:, C.POSITION])
    if mirror:
        px[:, 0] = camera.SIZE - px[:, 0]
        # Mirroring swaps handedness: an angle a becomes 180 - a, a counter-clockwise turn clockwise.
        out[:, C.ANGLE] = (180.0 - rows[:, C.ANGLE]) % 360.0
        out[:, C.TURN] = -rows[:, C.TURN]
    px[:, 0] += dcol
    px[:, 1] += drow
    out[:, C.POSITION] = camera.pixel_to_world(px, _z_to_unit_depth(rows[:, C.Z]))
    out[:, C.Z] = rows[:, C.Z]
    return out


def _shift_images(images: np.ndarray, dcol: int, drow: int) -> np.ndarray:
    """Translate (T, H, W, C) images, repeating the edge into the uncovered border."""
    h, w = images.shape[1:3]
    pad = max(abs(dcol), abs(drow))
    if pad == 0:
        return images
    padded = np.pad(images, ((0, 0), (pad, pad), (pad, pad), (0, 0)), mode="edge")
    r0, c0 = pad - drow, pad - dcol
    return padded[:, r0 : r0 + h, c0 : c0 + w]


def augment(
    images: np.ndarray,
    row_sets: list[np.ndarray],
    config: AugmentConfig,
    rng: np.random.Generator,
    noisy: list[bool] | None = None,
) -> tuple[np.ndarray, list[np.ndarray]]:
    """One random draw of the augmentation, applied alike to all images and all row sets.

    images: (T, H, W, 4). row_sets: arrays of affordance rows (ground-truth lists, executed
    actions). noisy: which row sets are executed actions and take action noise.
    """
    dcol = drow = 0
    if config.shift_px:
        dcol, drow = (int(v) for v in rng.integers(-config.shift_px, config.shift_px + 1, size=2))
    mirror = bool(config.mirror and rng.random() < 0.5)
    if mirror:
        images = images[:, :, ::-1]
    images = np.ascontiguousarray(_shift_images(images, dcol, drow))
    out = []
    for k, rows in enumerate(row_sets):
        rows = _move_rows(np.asarray(rows, dtype=np.float32), dcol, drow, mirror)
        if config.angle_flip and len(rows):
            # Symmetric affordances and turns do not depend on the gripper's direction.
            free = (rows[:, C.SYMMETRIC] > 0.5) | (rows[:, C.TURN] != 0)
            flip = free & (rng.random(len(rows)) < 0.5)
            rows[flip, C.ANGLE] = (rows[flip, C.ANGLE] + 180.0) % 360.0
        if noisy is not None and noisy[k] and len(rows):
            rows[:, C.XY] += (
                rng.normal(0, config.position_noise, size=(len(rows), 2)) if config.position_noise else 0
            )
            rows[:, C.ANGLE] = (
                rows[:, C.ANGLE] + (rng.normal(0, config.angle_noise, len(rows)) if config.angle_noise else 0)
            ) % 360
        out.append(rows.astype(np.float32))
    return images, out
