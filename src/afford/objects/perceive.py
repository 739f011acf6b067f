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

from afford.errors import UserError
from afford.objects.perception import AXIS_PAIRS, CHANNELS, OFFSET_SCALE, PerceptionNet
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
        # The images are (B, H, W, 4): as (B, 4, H, W) they are already channels-last, the
        # layout the net runs fastest in, so no copy is made.
        x = torch.from_numpy(np.asarray(images[i : i + BATCH], dtype=np.float32)).permute(0, 3, 1, 2)
        out = net.stacked(x)
        peaks, scores = centre_peaks(out[:, CHANNELS["heat"]], HEAT_CUT)
        kinds = out[:, CHANNELS["seg"]].argmax(1).numpy()
        # (B, H, W, C): an object's pixels' outputs are rows gathered in one step.
        pixels = out.permute(0, 2, 3, 1).numpy()
        found += [_objects(pixels[j], kinds[j], peaks[j], scores[j]) for j in range(len(x))]
    return found


def centre_peaks(logits: torch.Tensor, cut: float) -> tuple[list[np.ndarray], list[np.ndarray]]:
    """The peaks of (B, kinds, H, W) centre-map logits that reach `cut` (a probability): per
    image, their (kind, row, column) rows and their heights. A peak is at least as high as its
    eight neighbours. Only the few pixels above the cut are compared with their neighbours: a
    3 x 3 max pool over every pixel took a sixth of perception's time."""
    cand = torch.nonzero(logits > float(np.log(cut / (1 - cut))))  # (n, 4): image, kind, row, column
    image, kind, row, col = cand.T
    at = logits[image, kind, row, col]
    # A neighbour off the image's edge is clamped onto the edge: the pixel itself or one of its
    # true neighbours, so the comparison stays right without padding a copy of every map.
    h, w = logits.shape[2:]
    around = torch.stack(
        [
            logits[image, kind, (row + dr).clamp(0, h - 1), (col + dc).clamp(0, w - 1)]
            for dr in (-1, 0, 1)
            for dc in (-1, 0, 1)
        ]
    )
    keep = at >= around.amax(0)
    cand, heights = cand[keep].numpy(), torch.sigmoid(at[keep]).numpy()
    images = range(len(logits))
    return [cand[cand[:, 0] == i, 1:] for i in images], [heights[cand[:, 0] == i] for i in images]


def _objects(
    pixels: np.ndarray, kind_map: np.ndarray, peaks: np.ndarray, scores: np.ndarray
) -> list[SeenObject]:
    """One image's objects from its heads' outputs (H, W, C), its kind map, and its centre
    peaks as (kind, row, column) rows with their heights."""
    objects = []
    for k, kind in enumerate(KINDS):
        mine = peaks[:, 0] == k
        centres, heights = peaks[mine, 1:], scores[mine]  # (n, 2) row, column
        rows, cols = np.nonzero(kind_map == k + 1)
        if not len(centres) or not len(rows):
            continue
        seen = pixels[rows, cols]  # (n, C)
        votes = np.stack([cols + 0.5, rows + 0.5], 1) + seen[:, CHANNELS["offset"]] * OFFSET_SCALE
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
            mean = seen[mine].mean(0)  # every head's output, averaged over the object's pixels
            z = float(mean[CHANNELS["z"]][0]) / POS_SCALE
            up = mean[CHANNELS["up"]]
            if kind != "ball":  # the posture head decides the band; the up axis, the direction
                up = fit_posture(up, POSTURES[int(mean[CHANNELS["posture"]].argmax())])
            up = up / max(np.linalg.norm(up), 1e-9)
            along = _principal(mean[CHANNELS["along"]])
            mask = np.zeros(kind_map.shape, bool)
            mask[r, q] = True
            held = float((1 / (1 + np.exp(-seen[mine][:, CHANNELS["held"]]))).mean())
            objects.append(
                SeenObject(
                    kind,
                    pixel,
                    pixel_world(pixel, z),
                    up,
                    along,
                    mask,
                    held,
                    float(heights[c]),
                )
            )
    return objects


def _principal(products: np.ndarray) -> np.ndarray:
    """The long axis from the six entries of its outer product with itself (AXIS_PAIRS)."""
    product = np.zeros((3, 3))
    for value, (a, b) in zip(products, AXIS_PAIRS, strict=True):
        product[a, b] = product[b, a] = value
    return np.linalg.eigh(product)[1][:, -1]


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
