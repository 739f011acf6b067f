"""The affordance recognition net (paper II.B): a ScaledYOLOv4-style CSP detector on RGBD.

Backbone: Conv-BN-Mish blocks and CSP bottleneck stages down to stride 16, an SPP-CSP block,
then a top-down neck back to stride 4, where the one detection layer sits (a 32x32 grid on a
128x128 image, as the authors had). Per cell and angle anchor the head gives: confidence, type
logits, and for each type its own position offset, angle offset, z and symmetry. (Affordances
of different types share a point, e.g. grasp, turn and place at the block's centre; separate
regressions per type let each keep its own z and angle.)
"""

from __future__ import annotations

import copy

import torch
from torch import nn
from torch.nn.utils.fusion import fuse_conv_bn_eval

from afford.recognition.config import RecognitionConfig

REG = 5  # per type: x offset, y offset, angle offset, z, symmetry


class ConvBNMish(nn.Sequential):
    def __init__(self, c_in: int, c_out: int, k: int = 1, stride: int = 1):
        super().__init__(
            nn.Conv2d(c_in, c_out, k, stride, k // 2, bias=False),
            nn.BatchNorm2d(c_out),
            nn.Mish(inplace=True),
        )


class Bottleneck(nn.Module):
    def __init__(self, c: int):
        super().__init__()
        self.body = nn.Sequential(ConvBNMish(c, c, 1), ConvBNMish(c, c, 3))

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        return x + self.body(x)


class CSPStage(nn.Module):
    """Cross-stage partial block: half the channels go through the bottlenecks, half bypass."""

    def __init__(self, c_in: int, c_out: int, n: int):
        super().__init__()
        h = max(c_out // 2, 1)
        self.main = nn.Sequential(
            ConvBNMish(c_in, h, 1), *[Bottleneck(h) for _ in range(n)], nn.Conv2d(h, h, 1)
        )
        self.bypass = nn.Conv2d(c_in, h, 1, bias=False)
        self.merge = nn.Sequential(nn.BatchNorm2d(2 * h), nn.Mish(inplace=True), ConvBNMish(2 * h, c_out, 1))

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        return self.merge(torch.cat([self.main(x), self.bypass(x)], dim=1))


class SPPCSP(nn.Module):
    """Spatial pyramid pooling (5, 9, 13) inside a CSP split, as in ScaledYOLOv4."""

    def __init__(self, c: int):
        super().__init__()
        h = c // 2
        self.pre = nn.Sequential(ConvBNMish(c, h, 1), ConvBNMish(h, h, 3), ConvBNMish(h, h, 1))
        self.pools = nn.ModuleList(nn.MaxPool2d(k, 1, k // 2) for k in (5, 9, 13))
        self.post = nn.Sequential(ConvBNMish(4 * h, h, 1), ConvBNMish(h, h, 3))
        self.bypass = nn.Conv2d(c, h, 1, bias=False)
        self.merge = nn.Sequential(nn.BatchNorm2d(2 * h), nn.Mish(inplace=True), ConvBNMish(2 * h, c, 1))

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        y = self.pre(x)
        y = self.post(torch.cat([y, *(p(y) for p in self.pools)], dim=1))
        return self.merge(torch.cat([y, self.bypass(x)], dim=1))


class RecognitionNet(nn.Module):
    """(B, 4, H, W) RGBD in [0, 1] -> raw head output (B, anchors, G, G, per-anchor outputs)."""

    def __init__(self, config: RecognitionConfig):
        super().__init__()
        if config.stride != 4:
            raise ValueError("this net's neck ends at stride 4; config.stride must be 4")
        self.config = config
        w, d = config.widths, config.depths
        self.stem = nn.Sequential(ConvBNMish(config.in_channels, w[0], 3, 2), CSPStage(w[0], w[0], d[0]))
        self.s4 = nn.Sequential(ConvBNMish(w[0], w[1], 3, 2), CSPStage(w[1], w[1], d[1]))
        self.s8 = nn.Sequential(ConvBNMish(w[1], w[2], 3, 2), CSPStage(w[2], w[2], d[2]))
        self.s16 = nn.Sequential(ConvBNMish(w[2], w[3], 3, 2), CSPStage(w[3], w[3], d[3]), SPPCSP(w[3]))
        up = nn.Upsample(scale_factor=2, mode="nearest")
        self.up16 = nn.Sequential(ConvBNMish(w[3], w[2], 1), up)
        self.lat8 = ConvBNMish(w[2], w[2], 1)
        self.neck8 = CSPStage(2 * w[2], w[2], config.neck_depth)
        self.up8 = nn.Sequential(ConvBNMish(w[2], w[1], 1), up)
        self.lat4 = ConvBNMish(w[1], w[1], 1)
        self.neck4 = CSPStage(2 * w[1], w[1], config.neck_depth)
        self.n_out = 1 + len(config.types) + REG * len(config.types)
        self.head = nn.Sequential(
            ConvBNMish(w[1], 2 * w[1], 3), nn.Conv2d(2 * w[1], len(config.anchors) * self.n_out, 1)
        )
        # Start with a low confidence everywhere: few cells hold an affordance (YOLO's prior).
        with torch.no_grad():
            bias = self.head[-1].bias.view(len(config.anchors), self.n_out)
            bias[:, 0] = -6.0
        # Channels-last runs these small convolutions faster on CPUs (measured: ~1.2x training,
        # ~1.6x inference).
        self.to(memory_format=torch.channels_last)

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        c = self.config
        if x.ndim != 4 or x.shape[1] != c.in_channels or x.shape[2:] != (c.image_size, c.image_size):
            raise ValueError(
                f"recognition wants images of shape (B, {c.in_channels}, {c.image_size}, {c.image_size}), "
                f"got {tuple(x.shape)}"
            )
        f4 = self.s4(self.stem(x.contiguous(memory_format=torch.channels_last)))
        f8 = self.s8(f4)
        f16 = self.s16(f8)
        p8 = self.neck8(torch.cat([self.up16(f16), self.lat8(f8)], dim=1))
        p4 = self.neck4(torch.cat([self.up8(p8), self.lat4(f4)], dim=1))
        out = self.head(p4).permute(0, 2, 3, 1)  # (B, G, G, anchors * outputs)
        b, g = out.shape[:2]
        return out.reshape(b, g, g, len(c.anchors), self.n_out).permute(0, 3, 1, 2, 4)


# ---------------------------------------------------------------------------- inference
def _bn_slice(bn: nn.BatchNorm2d, start: int, stop: int) -> nn.BatchNorm2d:
    part = nn.BatchNorm2d(stop - start, eps=bn.eps).eval()
    with torch.no_grad():
        for name in ("weight", "bias", "running_mean", "running_var"):
            getattr(part, name).copy_(getattr(bn, name)[start:stop])
    return part


def _fold(conv: nn.Conv2d, bn: nn.BatchNorm2d) -> nn.Conv2d:
    return fuse_conv_bn_eval(conv.eval(), bn.eval())


@torch.no_grad()
def fused_for_inference(net: RecognitionNet) -> RecognitionNet:
    """A copy of `net` for inference with every batch norm folded into the convolution before
    it: the same outputs (to float rounding), one pass over memory less per layer.

    A CSP block normalises the concatenation of two branches, each channel made by one of two
    convolutions, so each half of that norm folds into its own branch's last convolution.
    """
    fused = copy.deepcopy(net).eval()
    for module in list(fused.modules()):
        if isinstance(module, ConvBNMish):
            module[0] = _fold(module[0], module[1])
            module[1] = nn.Identity()
        elif isinstance(module, (CSPStage, SPPCSP)):
            bn, h = module.merge[0], module.bypass.out_channels
            last = module.main[-1] if isinstance(module, CSPStage) else None
            if last is not None:
                module.main[-1] = _fold(last, _bn_slice(bn, 0, h))
            else:  # SPP-CSP: the main branch ends on its post block's Mish, so keep the norm there
                module.post.append(_bn_slice(bn, 0, h))
            module.bypass = _fold(module.bypass, _bn_slice(bn, h, 2 * h))
            module.merge[0] = nn.Identity()
    return fused.to(memory_format=torch.channels_last)
