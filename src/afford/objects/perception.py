"""E over objects: a net that sees the objects in one RGBD state image.

The recognition net's design (CSP stages; paper II.B) in an encoder to
stride 16 and a decoder back to stride 2, then one thin layer at full resolution: an object's
centre within a pixel and its mask's edge need every pixel, where the recognition net's single
stride-4 layer suffices for affordances. Per pixel the heads give
- `seg`: which kind of object is seen there (none, cup, ball, support, block);
- `heat`: per kind, how near an object's centre this pixel is (a Gaussian of `sigma_px`);
- `offset`: from the pixel to its object's centre, in pixels (pixels vote for their centre,
  which splits touching objects of one kind and gives the centre to a fraction of a pixel);
- the object's centre height `z`, its `up` axis, the outer product of its `along` axis with
  itself (the block's length has no sign, and a product of it with itself is continuous
  where a signed axis would flip), and whether it is `held`;
- `posture`: upright, tipped or lying, as a class. One object in thirty lies on its side, and
  a regressed up axis averaged those few into upright; a class scored with weights for the
  rare postures is not averaged away, and decoding makes the up axis agree with it.
Decoding the heads into objects is `perceive.py`.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

import numpy as np
import torch
from torch import nn
from torch.nn import functional as F

from afford.objects.state import KINDS, POS_SCALE, POSTURES, SLOT_KIND, posture, quat_axes
from afford.sim.camera import SIZE, world_to_pixel

# Output channels, in order.
HEADS = {
    "seg": 1 + len(KINDS),
    "heat": len(KINDS),
    "offset": 2,
    "z": 1,
    "up": 3,
    "along": 6,
    "held": 1,
    "posture": len(POSTURES),
}
# Each head's channels in the net's stacked output.
CHANNELS = {
    name: slice(sum(list(HEADS.values())[:i]), sum(list(HEADS.values())[: i + 1]))
    for i, name in enumerate(HEADS)
}
OFFSET_SCALE = 10.0  # offsets leave the net in tens of pixels
SEG_WEIGHT = torch.tensor([1.0] + [4.0] * len(KINDS))  # none, then each kind
AXIS_PAIRS = ((0, 0), (1, 1), (2, 2), (0, 1), (0, 2), (1, 2))  # the along product's entries
# Per posture (upright, tipped, lying), the weight of its pixels in the posture and up-axis
# losses: about the square root of how much rarer than upright each is in the generated data
# (non-ball objects: 90% upright, 6% tipped, 3.4% lying).
POSTURE_WEIGHT = torch.tensor([1.0, 4.0, 5.0])
NO_POSTURE = -100  # cross-entropy's ignore index: background, and balls (a sphere has no posture)


@dataclass
class PerceptionConfig:
    width: int = 16  # channels at half resolution; each further stride 2 doubles them
    depth: int = 1  # bottlenecks per CSP stage
    sigma_px: float = 1.5
    # training
    steps: int = 8000
    batch: int = 16
    lr: float = 2e-3
    warmup: int = 100
    weight_decay: float = 1e-4
    grad_clip: float = 5.0
    eval_every: int = 250
    log_every: int = 25
    seed: int = 0
    threads: int = 2

    # Fields that shipped files may store but this code does not vary: each with the one value
    # it runs (training/fields.from_dict refuses a stored config that asks for another).
    removed: ClassVar[dict[str, object]] = {"edge_weight": 1.0, "hidden": False, "hidden_trains_trunk": True}


PRESETS = {
    "cpu": PerceptionConfig(),
    "tiny": PerceptionConfig(width=4, steps=30, batch=4, eval_every=15, log_every=5),
}


class ConvBNReLU(nn.Sequential):
    def __init__(self, c_in: int, c_out: int, k: int = 1, stride: int = 1):
        super().__init__(
            nn.Conv2d(c_in, c_out, k, stride, k // 2, bias=False),
            nn.BatchNorm2d(c_out),
            nn.ReLU(inplace=True),
        )


def fold_batch_norms(net: nn.Module) -> nn.Module:
    """`net` (in eval mode, for inference only) with each batch norm folded into the convolution
    before it: the same outputs to float rounding, and on a CPU about twice as fast, since
    a batch norm reads and writes every activation once more. Not for training: the folded
    net has no batch statistics to learn."""
    from torch.nn.utils.fusion import fuse_conv_bn_eval

    net.eval()
    for m in net.modules():
        if isinstance(m, ConvBNReLU) and isinstance(m[1], nn.BatchNorm2d):
            m[0] = fuse_conv_bn_eval(m[0], m[1])
            m[1] = nn.Identity()
    return net


class CSPStage(nn.Module):
    """The recognition net's cross-stage partial stage (half the channels through residual
    bottlenecks, half around them), with ReLU for Mish: Mish took a third of the time here."""

    def __init__(self, c_in: int, c_out: int, n: int):
        super().__init__()
        h = max(c_out // 2, 1)
        self.enter = ConvBNReLU(c_in, h, 1)
        self.blocks = nn.ModuleList(nn.Sequential(ConvBNReLU(h, h, 1), ConvBNReLU(h, h, 3)) for _ in range(n))
        self.bypass = ConvBNReLU(c_in, h, 1)
        self.merge = ConvBNReLU(2 * h, c_out, 1)

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        y = self.enter(x)
        for b in self.blocks:
            y = y + b(y)
        return self.merge(torch.cat([y, self.bypass(x)], 1))


class PerceptionNet(nn.Module):
    def __init__(self, config: PerceptionConfig):
        super().__init__()
        self.config = config
        w = config.width
        # RGBD plus the pixel's place in the image: a held object is told by where it is seen.
        self.stem = ConvBNReLU(6, w, 3, 2)
        self.down = nn.ModuleList(
            nn.Sequential(
                ConvBNReLU(w * 2**i, w * 2 ** (i + 1), 3, 2),
                CSPStage(w * 2 ** (i + 1), w * 2 ** (i + 1), config.depth),
            )
            for i in range(3)
        )
        self.up = nn.ModuleList(
            CSPStage(w * 2 ** (i + 1) + w * 2**i, w * 2**i, config.depth) for i in reversed(range(3))
        )
        # The work is done at half resolution; one thin layer at full resolution, with the image
        # itself beside the features, puts masks' edges and centres on the right pixel.
        self.refine = ConvBNReLU(w + 6, w // 2, 3)
        self.head = nn.Conv2d(w // 2, sum(HEADS.values()), 1)
        with torch.no_grad():  # centre maps start near 0, as they mostly are (CenterNet's prior)
            self.head.bias[CHANNELS["heat"]] = -4.0
        ys, xs = torch.meshgrid(torch.linspace(-1, 1, SIZE), torch.linspace(-1, 1, SIZE), indexing="ij")
        self.register_buffer("coords", torch.stack([xs, ys])[None], persistent=False)

    def forward(self, images: torch.Tensor) -> dict[str, torch.Tensor]:
        """(B, 4, H, W) RGBD in [0, 1] -> each head's (B, C, H, W) output (raw logits)."""
        split = torch.split(self.stacked(images), list(HEADS.values()), dim=1)
        return dict(zip(HEADS, split, strict=True))

    def stacked(self, images: torch.Tensor) -> torch.Tensor:
        """The heads' outputs in one (B, C, H, W) tensor, channels as in CHANNELS."""
        full = torch.cat([images, self.coords.expand(len(images), -1, -1, -1)], 1)
        x = self.stem(full)
        skips = [x]
        for d in self.down:
            x = d(x)
            skips.append(x)
        skips.pop()
        for u in self.up:
            x = F.interpolate(x, scale_factor=2, mode="nearest")
            x = u(torch.cat([x, skips.pop()], 1))
        x = F.interpolate(x, scale_factor=2, mode="bilinear", align_corners=False)
        return self.head(self.refine(torch.cat([x, full], 1)))


# ---------------------------------------------------------------------------- targets
def targets(
    masks: np.ndarray, poses: np.ndarray, held: np.ndarray, sigma_px: float
) -> dict[str, torch.Tensor]:
    """Per-pixel targets of B images from their instance masks (B, H, W) (slot or -1), true
    poses (B, slots, 7) and held slots (B,)."""
    b = len(masks)
    rows, cols = np.mgrid[0:SIZE, 0:SIZE]
    px = np.stack([cols + 0.5, rows + 0.5])  # pixel centres as (column, row)
    seg = np.zeros((b, SIZE, SIZE), np.int64)
    heat = np.zeros((b, len(KINDS), SIZE, SIZE), np.float32)
    offset = np.zeros((b, 2, SIZE, SIZE), np.float32)
    z = np.zeros((b, 1, SIZE, SIZE), np.float32)
    up = np.zeros((b, 3, SIZE, SIZE), np.float32)
    along = np.zeros((b, 6, SIZE, SIZE), np.float32)
    is_held = np.zeros((b, 1, SIZE, SIZE), np.float32)
    stance = np.full((b, SIZE, SIZE), NO_POSTURE, np.int64)
    for i in range(b):
        for slot in np.unique(masks[i]):
            if slot < 0 or np.isnan(poses[i, slot, 0]):
                continue
            where = masks[i] == slot
            kind = SLOT_KIND[slot]
            centre = world_to_pixel(poses[i, slot, :3].astype(float))
            seg[i][where] = kind + 1
            _mark_centre(heat[i, kind], centre, px, sigma_px)
            offset[i][:, where] = (centre[:, None] - px[:, where]) / OFFSET_SCALE
            z[i, 0][where] = poses[i, slot, 2] * POS_SCALE
            u, a = quat_axes(poses[i, slot, 3:7].astype(float))
            up[i][:, where] = u[:, None]
            along[i][:, where] = np.array([a[p] * a[q] for p, q in AXIS_PAIRS])[:, None]
            is_held[i, 0][where] = float(slot == held[i])
            if KINDS[kind] != "ball":
                stance[i][where] = POSTURES.index(posture(float(u[2])))
    t = torch.from_numpy
    return {
        "seg": t(seg),
        "heat": t(heat),
        "offset": t(offset),
        "z": t(z),
        "up": t(up),
        "along": t(along),
        "held": t(is_held),
        "posture": t(stance),
    }


def _mark_centre(heat: np.ndarray, centre: np.ndarray, px: np.ndarray, sigma_px: float) -> np.ndarray:
    """Draw an object's centre into a centre map (H, W) in place: a Gaussian around it, kept
    where it is higher than what the map holds, and 1 at the pixel holding the centre, the peak
    whatever fraction of a pixel it is off. Returns the Gaussian."""
    near = np.exp(-((px[0] - centre[0]) ** 2 + (px[1] - centre[1]) ** 2) / (2 * sigma_px**2))
    np.maximum(heat, near, out=heat)
    col, row = np.clip(np.floor(centre).astype(int), 0, SIZE - 1)
    heat[row, col] = 1.0
    return near


def focal_heat(logits: torch.Tensor, target: torch.Tensor) -> torch.Tensor:
    """CenterNet's penalty-reduced focal loss on Gaussian centre maps, per centre."""
    p = torch.sigmoid(logits).clamp(1e-4, 1 - 1e-4)
    peak = target > 0.99
    pos = -((1 - p) ** 2) * torch.log(p) * peak
    neg = -((1 - target) ** 4) * p**2 * torch.log(1 - p) * ~peak
    return (pos.sum() + neg.sum()) / peak.sum().clamp(min=1)


def loss(out: dict[str, torch.Tensor], t: dict[str, torch.Tensor]) -> tuple[torch.Tensor, dict[str, float]]:
    obj = (t["seg"] > 0).float()[:, None]
    n = obj.sum().clamp(min=1)
    seg_weight = SEG_WEIGHT.to(out["seg"])
    kind = F.cross_entropy(out["seg"], t["seg"], weight=seg_weight, reduction="none")
    offset = F.smooth_l1_loss(out["offset"], t["offset"], reduction="none", beta=0.05) * obj
    weights = POSTURE_WEIGHT.to(out["posture"])
    # A ball's up axis still counts (it is drawn with it), at the weight of upright.
    rare = torch.where(t["posture"] >= 0, weights[t["posture"].clamp(min=0)], 1.0)[:, None] * obj
    parts = {
        # Objects cover a tenth of the image: their pixels weigh more, or the table wins.
        "seg": kind.sum() / seg_weight[t["seg"]].sum(),
        "heat": focal_heat(out["heat"], t["heat"]),
        "offset": offset.sum() / obj.sum().clamp(min=1),
        "z": (F.smooth_l1_loss(out["z"], t["z"], reduction="none", beta=0.05) * obj).sum() / n,
        "up": ((out["up"] - t["up"]) ** 2 * rare).sum() / rare.sum().clamp(min=1),
        "along": ((out["along"] - t["along"]) ** 2 * obj).sum() / n,
        "held": (F.binary_cross_entropy_with_logits(out["held"], t["held"], reduction="none") * obj).sum()
        / n,
        "posture": F.cross_entropy(out["posture"], t["posture"], weight=weights, ignore_index=NO_POSTURE)
        if (t["posture"] >= 0).any()
        else out["posture"].sum() * 0.0,
    }
    total = (
        parts["seg"]
        + parts["heat"]
        + 10 * parts["offset"]
        + 10 * parts["z"]
        + parts["up"]
        + parts["along"]
        + parts["held"]
        + parts["posture"]
    )
    return total, {k: float(v.detach()) for k, v in parts.items()}
