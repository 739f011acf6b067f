"""Targets, losses and decoding for the recognition net's one detection layer (paper II.B).

Image geometry goes through the simulator's camera model only: a world point projects to a
continuous pixel (column, row); the grid cell is pixel // stride. Per cell and angle anchor
(0/90/180/270 degrees) the raw output holds

    [confidence | type logits (T) | per type: x offset, y offset, angle offset, z, symmetry]

x/y offsets are sigmoid * 2 - 0.5 cells, so a cell can also claim a point in its neighbours
(as in YOLO, each target goes to its own cell and the two nearest neighbour cells); the angle
offset is 45 * tanh degrees around the anchor; z is regressed as z * z_scale metres.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import torch
import torch.nn.functional as F

from afford.recognition.config import RecognitionConfig
from afford.recognition.model import REG
from afford.sim import camera
from afford.sim.affordance import AFF_WIDTH, Affordance, Col, Detection
from afford.sim.constants import CAMERA
from afford.sim.geometry import wrap180

ANCHOR_HALF_WIDTH = 45.0


@dataclass
class Targets:
    obj: torch.Tensor  # (B, A, G, G) 1 where an affordance is assigned
    types: torch.Tensor  # (B, A, G, G, T) multi-label
    reg: torch.Tensor  # (B, A, G, G, T, 5) x offset, y offset, angle offset / 45, z * z_scale, symmetric
    reg_mask: torch.Tensor  # (B, A, G, G, T) bool: which type's regression is supervised


def anchor_of(angle: np.ndarray, config: RecognitionConfig) -> tuple[np.ndarray, np.ndarray]:
    """The anchor within 45 degrees of each angle, and the offset from it in [-45, 45)."""
    anchors = np.asarray(config.anchors)
    diff = wrap180(np.asarray(angle)[..., None] - anchors)
    k = np.argmin(np.abs(diff), axis=-1)
    return k, np.take_along_axis(diff, k[..., None], axis=-1)[..., 0]


def build_targets(rows_list: list[np.ndarray | torch.Tensor], config: RecognitionConfig) -> Targets:
    """Assign each true affordance (world-frame rows, format.AFF_COLUMNS) to cells and an anchor."""
    b, a, g, t = len(rows_list), len(config.anchors), config.grid, len(config.types)
    obj = torch.zeros((b, a, g, g))
    types = torch.zeros((b, a, g, g, t))
    reg = torch.zeros((b, a, g, g, t, REG))
    mask = torch.zeros((b, a, g, g, t), dtype=torch.bool)
    for i, rows in enumerate(rows_list):
        rows = np.asarray(rows, dtype=np.float64).reshape(-1, AFF_WIDTH)
        if len(rows) == 0:
            continue
        grid_xy = camera.world_to_pixel(rows[:, Col.POSITION]) / config.stride
        k, off = anchor_of(rows[:, Col.ANGLE], config)
        for r in range(len(rows)):
            gx, gy = grid_xy[r]
            cx, cy = int(np.floor(gx)), int(np.floor(gy))
            cells = [(cx, cy)]
            if config.neighbours:
                cells.append((cx - 1 if gx - cx < 0.5 else cx + 1, cy))
                cells.append((cx, cy - 1 if gy - cy < 0.5 else cy + 1))
            typ = int(rows[r, Col.TYPE])
            for x, y in cells:
                if not (0 <= x < g and 0 <= y < g):
                    continue
                obj[i, k[r], y, x] = 1.0
                types[i, k[r], y, x, typ] = 1.0
                reg[i, k[r], y, x, typ] = torch.tensor(
                    [
                        gx - x,
                        gy - y,
                        off[r] / ANCHOR_HALF_WIDTH,
                        rows[r, Col.Z] * config.z_scale,
                        rows[r, Col.SYMMETRIC],
                    ]
                )
                mask[i, k[r], y, x, typ] = True
    return Targets(obj, types, reg, mask)


def _split(raw: torch.Tensor, config: RecognitionConfig):
    t = len(config.types)
    conf = raw[..., 0]
    type_logits = raw[..., 1 : 1 + t]
    reg = raw[..., 1 + t :].reshape(*raw.shape[:-1], t, REG)
    xy = torch.sigmoid(reg[..., :2]) * 2 - 0.5
    angle = torch.tanh(reg[..., 2])
    return conf, type_logits, xy, angle, reg[..., 3], reg[..., 4]


def quality(
    xy: torch.Tensor, angle: torch.Tensor, targets: Targets, config: RecognitionConfig
) -> torch.Tensor:
    """(B, A, G, G) how well each positive cell's own regression hits its affordance, in (0, 1]:
    a Gaussian of its position error (cells) and angle error (degrees; none for a symmetric
    one), widths half Table 1's hit criteria; the best of its types. 0 at negative cells."""
    d_xy = (xy - targets.reg[..., :2]).norm(dim=-1)  # (B, A, G, G, T)
    d_angle = (angle - targets.reg[..., 2]) * ANCHOR_HALF_WIDTH * (1 - targets.reg[..., 4])
    q = torch.exp(-0.5 * (d_xy / config.quality_cells) ** 2 - 0.5 * (d_angle / config.quality_degrees) ** 2)
    return (q * targets.reg_mask).amax(-1)


def loss(
    raw: torch.Tensor, targets: Targets, config: RecognitionConfig
) -> tuple[torch.Tensor, dict[str, float]]:
    """BCE for confidence and type, MSE for offsets, angle, z and symmetry (paper II.B), each
    true affordance's terms weighted by `config.type_weights` (a rare type weighs more).

    With `config.conf_quality` the confidence target at a positive cell is lowered by how far
    off the cell's own regression is (the authors' choice, from YOLO): of the cells that claim
    an affordance, the most accurate then scores highest and survives suppression, and a cell
    whose angle is off scores low instead of becoming a confident spurious detection."""
    conf, type_logits, xy, angle, z, sym = _split(raw, config)
    given = list(config.type_weights)[: len(config.types)]
    type_weights = raw.new_tensor(given + [1.0] * (len(config.types) - len(given)))  # unlisted types: 1
    # A positive cell weighs as its heaviest type; negatives weigh 1.
    cell_weight = torch.where(
        targets.obj > 0, (targets.types * type_weights).amax(-1), torch.ones_like(targets.obj)
    )
    n_pos = targets.obj.sum().clamp(min=1.0)
    conf_target = targets.obj
    if config.conf_quality:
        mix = config.conf_quality
        conf_target = targets.obj * ((1 - mix) + mix * quality(xy, angle, targets, config).detach())
    l_conf = (
        F.binary_cross_entropy_with_logits(conf, conf_target, reduction="none") * cell_weight
    ).sum() / n_pos
    pos = targets.obj > 0
    l_type = (
        (
            F.binary_cross_entropy_with_logits(type_logits[pos], targets.types[pos], reduction="none")
            * cell_weight[pos][:, None]
        ).mean()
        if pos.any()
        else raw.sum() * 0
    )
    m = targets.reg_mask
    if m.any():
        tr = targets.reg[m]
        w = type_weights.expand(m.shape)[m]  # each supervised entry weighs as its type
        l_xy = ((xy[m] - tr[:, :2]) ** 2 * w[:, None]).mean()
        l_angle = ((angle[m] - tr[:, 2]) ** 2 * w).mean()
        l_z = ((z[m] - tr[:, 3]) ** 2 * w).mean()
        l_sym = ((torch.sigmoid(sym[m]) - tr[:, 4]) ** 2 * w).mean()
    else:
        l_xy = l_angle = l_z = l_sym = raw.sum() * 0
    total = (
        config.w_conf * l_conf
        + config.w_type * l_type
        + config.w_xy * l_xy
        + config.w_angle * l_angle
        + config.w_z * l_z
        + config.w_sym * l_sym
    )
    parts = {"conf": l_conf, "type": l_type, "xy": l_xy, "angle": l_angle, "z": l_z, "sym": l_sym}
    return total, {k: float(v.detach()) for k, v in parts.items()}


@torch.no_grad()
def decode(
    raw: torch.Tensor, config: RecognitionConfig, threshold: float | None = None
) -> list[list[Detection]]:
    """Raw head output -> per image, detections above the cut-off, before suppression."""
    threshold = config.confidence if threshold is None else threshold
    conf, type_logits, xy, angle, z, sym = _split(raw.float(), config)
    score = torch.sigmoid(conf)[..., None] * torch.sigmoid(type_logits)  # (B, A, G, G, T)
    out: list[list[Detection]] = [[] for _ in range(raw.shape[0])]
    idx = torch.nonzero(score > threshold)
    if len(idx) == 0:
        return out
    bi, ai, yi, xi, ti = idx.unbind(1)
    s = score[bi, ai, yi, xi, ti].numpy()
    off = xy[bi, ai, yi, xi, ti].numpy()
    cols = (xi.numpy() + off[:, 0]) * config.stride
    rows = (yi.numpy() + off[:, 1]) * config.stride
    zs = z[bi, ai, yi, xi, ti].numpy() / config.z_scale
    world = camera.pixel_to_world(np.stack([cols, rows], -1), camera.depth_to_unit(CAMERA.pos[2] - zs))
    anchors = np.asarray(config.anchors)[ai.numpy()]
    angles = (anchors + ANCHOR_HALF_WIDTH * angle[bi, ai, yi, xi, ti].numpy()) % 360.0
    symmetric = torch.sigmoid(sym[bi, ai, yi, xi, ti]).numpy() > 0.5
    for j in range(len(s)):
        aff = Affordance(
            config.types[int(ti[j])],
            (float(world[j, 0]), float(world[j, 1]), float(zs[j])),
            float(angles[j]),
            bool(symmetric[j]),
        )
        out[int(bi[j])].append(Detection(aff, float(s[j])))
    return out


def suppress(detections: list[Detection], radius: float, max_angle: float) -> list[Detection]:
    """Drop detections near a more confident one of the same type (paper II.B's separate step).

    Near: within `radius` metres in the table plane and `max_angle` degrees, or any angle when
    either is symmetric (other angles of a symmetric affordance give the same result).
    """
    kept: list[Detection] = []
    for d in sorted(detections, key=lambda d: -d.score):
        a = d.affordance
        duplicate = any(
            k.affordance.type == a.type
            and np.hypot(k.affordance.position[0] - a.position[0], k.affordance.position[1] - a.position[1])
            < radius
            and (
                a.symmetric
                or k.affordance.symmetric
                or abs(wrap180(k.affordance.angle - a.angle)) < max_angle
            )
            for k in kept
        )
        if not duplicate:
            kept.append(d)
    return kept
