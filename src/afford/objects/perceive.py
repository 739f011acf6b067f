"""From the perception net's heads to a list of objects, and from objects to a state.

Per kind, the centres are the peaks of that kind's heat map; every pixel the net calls that
kind votes for a centre (its position plus its offset) and joins the peak nearest its vote.
An object's centre is the median of its pixels' votes, its height, axes and held score the mean
over its pixels: each is read from many pixels, not one.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import torch
from torch.nn import functional as F

from afford.errors import UserError
from afford.objects.perception import AXIS_PAIRS, OFFSET_SCALE, PerceptionNet
from afford.objects.state import (
    KINDS,
    N_SLOTS,
    POS_SCALE,
    POSTURES,
    SLOT_KIND,
    axes_quat,
    fit_posture,
    posture,
)
from afford.sim.camera import FOCAL_PX, SIZE
from afford.sim.constants import CAMERA

HEAT_CUT = 0.3  # a centre map's peak at least this high is an object
ASSIGN_PX = 6.0  # a pixel whose vote lands farther than this from every centre joins none
MIN_PIXELS = 3  # fewer pixels than this: noise, not an object
BATCH = 64


@dataclass
class SeenObject:
    """One object perceived in a state image."""

    kind: str
    pixel: np.ndarray  # centre (column, row), continuous
    position: np.ndarray  # world (x, y, z), metres
    up: np.ndarray  # its z axis in the world
    along: np.ndarray  # its x axis (the block's length), either sign
    mask: np.ndarray  # (H, W) bool: the pixels it was seen in
    held: float  # probability that the gripper holds it
    score: float  # its centre map's peak

    @property
    def posture(self) -> str:
        return posture(float(self.up[2]))

    @property
    def quat(self) -> np.ndarray:
        return axes_quat(self.up, self.along)


def pixel_world(pixel: np.ndarray, z: float) -> np.ndarray:
    """A pixel (column, row) and a world height -> the world point seen there at that height."""
    depth = CAMERA.pos[2] - z
    x = CAMERA.pos[0] + (pixel[0] - SIZE / 2) * depth / FOCAL_PX
    y = CAMERA.pos[1] - (pixel[1] - SIZE / 2) * depth / FOCAL_PX
    return np.array([x, y, z])


@torch.no_grad()
def perceive(net: PerceptionNet, images: np.ndarray) -> list[list[SeenObject]]:
    """The objects in each of (B, H, W, 4) RGBD images."""
    if images.ndim != 4 or images.shape[1:] != (SIZE, SIZE, 4):
        raise UserError(
            f"perception takes {SIZE} x {SIZE} RGBD state images, not an array of shape {images.shape}"
        )
    net.eval()
    found = []
    for i in range(0, len(images), BATCH):
        x = torch.from_numpy(
            np.ascontiguousarray(images[i : i + BATCH].transpose(0, 3, 1, 2), dtype=np.float32)
        )
        out = net(x)
        heat = torch.sigmoid(out["heat"])
        peaks = (heat == F.max_pool2d(heat, 3, 1, 1)) & (heat > HEAT_CUT)
        arrays = {k: v.numpy() for k, v in out.items()}
        kinds = out["seg"].argmax(1).numpy()
        for j in range(len(x)):
            found.append(
                _objects({k: v[j] for k, v in arrays.items()}, kinds[j], peaks[j].numpy(), heat[j].numpy())
            )
    return found


def _objects(
    out: dict[str, np.ndarray], kind_map: np.ndarray, peaks: np.ndarray, heat: np.ndarray
) -> list[SeenObject]:
    objects = []
    for k, kind in enumerate(KINDS):
        centres = np.argwhere(peaks[k])  # (n, 2) row, column
        rows, cols = np.nonzero(kind_map == k + 1)
        if not len(centres) or not len(rows):
            continue
        votes = np.stack([cols + 0.5, rows + 0.5], 1) + out["offset"][:, rows, cols].T * OFFSET_SCALE
        at = centres[:, ::-1] + 0.5  # peaks as (column, row) pixel centres
        dist = np.linalg.norm(votes[:, None] - at[None], axis=-1)
        nearest = dist.argmin(1)
        near = dist[np.arange(len(votes)), nearest] <= ASSIGN_PX
        for c in range(len(centres)):
            mine = near & (nearest == c)
            if mine.sum() < MIN_PIXELS:
                continue
            r, q = rows[mine], cols[mine]
            pixel = np.median(votes[mine], 0)
            z = float(out["z"][0, r, q].mean()) / POS_SCALE
            up = out["up"][:, r, q].mean(1)
            if kind != "ball":  # the posture head decides the band; the up axis, the direction
                up = fit_posture(up, POSTURES[int(out["posture"][:, r, q].mean(1).argmax())])
            up = up / max(np.linalg.norm(up), 1e-9)
            product = np.zeros((3, 3))
            for value, (a, b) in zip(out["along"][:, r, q].mean(1), AXIS_PAIRS, strict=True):
                product[a, b] = product[b, a] = value
            along = np.linalg.eigh(product)[1][:, -1]  # the principal axis of along x along
            mask = np.zeros(kind_map.shape, bool)
            mask[r, q] = True
            held = float(1 / (1 + np.exp(-out["held"][0, r, q])).mean())
            objects.append(
                SeenObject(
                    kind,
                    pixel,
                    pixel_world(pixel, z),
                    up,
                    along,
                    mask,
                    held,
                    float(heat[k, centres[c][0], centres[c][1]]),
                )
            )
    return objects


def by_slot(objects: list[SeenObject]) -> list[SeenObject | None]:
    """Perceived objects in the dynamics' slots (None: empty). Each kind's objects fill that
    kind's slots, the most confident first; the dynamics treat slots of one kind alike, so
    which goes where is free."""
    slots: list[SeenObject | None] = [None] * N_SLOTS
    for k, kind in enumerate(KINDS):
        mine = sorted((o for o in objects if o.kind == kind), key=lambda o: -o.score)
        for slot, o in zip(np.flatnonzero(SLOT_KIND == k), mine, strict=False):
            slots[slot] = o
    return slots


def to_state(objects: list[SeenObject]) -> tuple[np.ndarray, int]:
    """Perceived objects as a state the dynamics take: pose rows (slots, 7) (NaN: no object
    there) and the held slot (-1: none), the slots filled as `by_slot` fills them."""
    poses = np.full((N_SLOTS, 7), np.nan, np.float32)
    held, best = -1, 0.5
    for slot, o in enumerate(by_slot(objects)):
        if o is None:
            continue
        poses[slot] = np.concatenate([o.position, o.quat])
        if o.held > best:
            held, best = slot, o.held
    return poses, held


def slot_masks(objects: list[SeenObject]) -> np.ndarray:
    """(slots, H, W) bool: the pixels each slot's object was seen in (none for an empty slot)."""
    masks = np.zeros((N_SLOTS, SIZE, SIZE), bool)
    for slot, o in enumerate(by_slot(objects)):
        if o is not None:
            masks[slot] = o.mask
    return masks
