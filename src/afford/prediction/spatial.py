"""The `cpu` preset's E, P^a and D: the EM*D pathway with a spatial latent (paper II.C, ours).

The paper's latent is a dense vector of 128 values; decoding a whole scene from it takes the
paper's million batches. Here the latent c is a grid (latent_channels x 16 x 16): E is a stack
of strided convolutions, each P^a a stack of residual convolution blocks on that grid, D a
stack of nearest-neighbour 2x upsamplings and convolutions back to 128 x 128. What stays the
paper's: E; one P^a per affordance type, picked by the action's type; a memory trace handed
from one P to the next (zeros at the first step); c_{i+1} = c_i + dc (eq. 2); D decoding dc to
an (n+1)-channel difference image whose last channel is the mask of eq. (3); the affordance's
pixel read from the current (real, then predicted) image.

Two things a grid needs that a vector does not:
- The action enters P as maps on the grid: a Gaussian blob at the affordance's pixel, times
  each action value (angle as cos/sin, turn, z, the pixel's RGBD).
- A coarse path spans the whole image in every block: the grid's features pooled three ways
  (the mean, under the action's blob, under a learned attention map) and added back to every
  cell, so what is grasped at one spot can appear in the gripper at the bottom of the image,
  and what the gripper holds can appear at the place point.
D also sees the current image at full resolution in its last convolution (a skip, ours), so
the mask and the difference can follow the edges of what is there instead of a 16 x 16 blur.
"""

from __future__ import annotations

import math

import torch
from torch import nn

from afford.prediction.config import PredictionConfig
from afford.prediction.layers import clamped_tanh
from afford.sim.camera import SIZE

# D's mask starts nearly closed (clamped tanh(MASK_BIAS)): eq. (3) first copies the state. Not
# fully closed, or neither the mask nor the difference would get a gradient.
MASK_BIAS = 0.1

ACTIVATIONS = {"tanh": nn.Tanh, "gelu": nn.GELU, "silu": nn.SiLU}

# Channels of the action maps: blob, blob*(cos a, sin a, cos 2a, sin 2a, turn, z), blob*RGBD.
ACTION_MAPS = 7


def _conv(a: int, b: int, stride: int = 1, k: int = 3) -> nn.Conv2d:
    return nn.Conv2d(a, b, k, stride, k // 2)


class SpatialEncoder(nn.Module):
    """E: strided convolutions, 128 x 128 x 4 -> latent_channels x 16 x 16."""

    def __init__(self, c: PredictionConfig):
        super().__init__()
        act = ACTIVATIONS[c.model.activation]
        layers: list[nn.Module] = []
        width = c.model.channels
        for w in c.model.encoder_channels:
            layers += [_conv(width, w, stride=2), act()]
            width = w
        # tanh keeps c in [-1, 1]: P's residual sums stay of order 1 (the dense net normalises).
        layers += [_conv(width, c.model.latent_channels, k=1), nn.Tanh()]
        self.net = nn.Sequential(*layers)
        self.memory_channels = c.model.memory_channels

    def forward(self, image: torch.Tensor) -> torch.Tensor:
        return self.net(image)

    def initial_memory(self, latent: torch.Tensor) -> torch.Tensor:
        """The memory trace before the first step: zeros (paper II.C)."""
        b, _, h, w = latent.shape
        return latent.new_zeros(b, self.memory_channels, h, w)

    def renormalise(self, latent: torch.Tensor) -> torch.Tensor:
        return latent  # eq. (2) exactly: the grid needs no re-normalisation


def action_maps(vector: torch.Tensor, pixel: torch.Tensor, size: int, sigma: float) -> torch.Tensor:
    """The action as (B, ACTION_MAPS, size, size) maps on the latent grid.

    vector: the action vector (B, 9: x, y, z, angle as a fraction of a turn, turn, RGBD);
    pixel: the affordance's continuous (column, row) in the 128 x 128 image.
    """
    cell = pixel * (size / SIZE) - 0.5  # continuous grid coordinates of the cell centres
    grid = torch.arange(size, dtype=vector.dtype, device=vector.device)
    gx = torch.exp(-0.5 * ((grid[None, :] - cell[:, :1]) / sigma) ** 2)  # (B, size) along columns
    gy = torch.exp(-0.5 * ((grid[None, :] - cell[:, 1:]) / sigma) ** 2)  # (B, size) along rows
    blob = gy[:, :, None] * gx[:, None, :]  # (B, size, size), peak 1 at the affordance
    angle = 2 * math.pi * vector[:, 3]
    values = torch.stack(
        [
            torch.ones_like(angle),
            torch.cos(angle),
            torch.sin(angle),
            torch.cos(2 * angle),
            torch.sin(2 * angle),
            vector[:, 4],
            vector[:, 2],
        ],
        1,
    )
    values = torch.cat([values, vector[:, 5:]], 1)
    return blob[:, None] * values[:, :, None, None]


class GlobalPath(nn.Module):
    """The coarse path: features pooled over the whole grid, added back to every cell."""

    def __init__(self, width: int, act: type[nn.Module]):
        super().__init__()
        self.attention = nn.Conv2d(width, 1, 1)
        self.mix = nn.Sequential(nn.Linear(3 * width, width), act(), nn.Linear(width, width))

    def forward(self, h: torch.Tensor, blob: torch.Tensor) -> torch.Tensor:
        mean = h.mean((2, 3))
        at_action = (h * blob).sum((2, 3)) / blob.sum((2, 3)).clamp_min(1e-6)
        weights = torch.softmax(self.attention(h).flatten(1), -1).view_as(blob)
        attended = (h * weights).sum((2, 3))
        return self.mix(torch.cat([mean, at_action, attended], 1))[:, :, None, None]


class Block(nn.Module):
    """A residual block: two 3x3 convolutions on the grid, plus the coarse path."""

    def __init__(self, width: int, act: type[nn.Module]):
        super().__init__()
        self.conv1, self.conv2 = _conv(width, width), _conv(width, width)
        self.act = act()
        self.coarse = GlobalPath(width, act)
        with torch.no_grad():  # start near the identity: deep residual stacks train from the start
            self.conv2.weight.mul_(0.1)
            self.conv2.bias.zero_()

    def forward(self, h: torch.Tensor, blob: torch.Tensor) -> torch.Tensor:
        x = self.act(self.conv1(self.act(h)) + self.coarse(h, blob))
        return h + self.conv2(x)


def _out_conv(c: PredictionConfig) -> nn.Conv2d:
    out = _conv(c.model.p_channels, c.model.latent_channels + c.model.memory_channels)
    with torch.no_grad():  # dc starts small: eq. (2) first keeps c
        out.weight.mul_(0.1)
        out.bias.zero_()
    return out


class Fork(nn.Module):
    """Another outcome's own end of P^a (`fork="latent"`): a copy of its last block and its
    output layer, so each candidate outcome has its own dc, and the latent itself forks."""

    def __init__(self, c: PredictionConfig, act: type[nn.Module]):
        super().__init__()
        self.block = Block(c.model.p_channels, act)
        self.out = _out_conv(c)


class SpatialP(nn.Module):
    """One affordance type's P^a on the grid: (c_i, m_i, action) -> (dc, m_{i+1}).

    With `fork="latent"` and K hypotheses, dc (B, K, ...) and m_{i+1} (B, K, ...): the first
    outcome through `blocks` and `out` as with one, the others through their `forks`, which
    branch before the last block.
    """

    def __init__(self, c: PredictionConfig):
        super().__init__()
        act = ACTIVATIONS[c.model.activation]
        self.size, self.sigma = c.model.latent_size, c.model.blob_sigma
        self.latent_channels = c.model.latent_channels
        self.action_channels = ACTION_MAPS + c.model.channels
        self.inp = _conv(
            c.model.latent_channels + c.model.memory_channels + self.action_channels, c.model.p_channels
        )
        self.blocks = nn.ModuleList(Block(c.model.p_channels, act) for _ in range(c.model.p_blocks))
        self.act = act()
        self.out = _out_conv(c)
        forked = c.outcomes.hypotheses if c.outcomes.fork == "latent" else 1
        self.forks = nn.ModuleList(Fork(c, act) for _ in range(forked - 1))
        self.shared = c.model.p_blocks - (1 if self.forks else 0)

    def forward(self, latent: torch.Tensor, memory: torch.Tensor, vector: torch.Tensor, pixel: torch.Tensor):
        maps = action_maps(vector, pixel, self.size, self.sigma)
        blob = maps[:, :1]
        h = self.inp(torch.cat([latent, memory, maps], 1))
        for block in self.blocks[: self.shared]:
            h = block(h, blob)
        if not self.forks:
            return self._split(self.out(self.act(h)))
        ends = [(self.blocks[-1], self.out)] + [(f.block, f.out) for f in self.forks]
        outs = [self._split(out(self.act(block(h, blob)))) for block, out in ends]
        return torch.stack([o[0] for o in outs], 1), torch.stack([o[1] for o in outs], 1)

    def _split(self, out: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
        return out[:, : self.latent_channels], torch.tanh(out[:, self.latent_channels :])


class SpatialDecoder(nn.Module):
    """D: dc -> (n+1)-channel difference image, by 2x nearest upsampling and convolutions.

    The last stage works at half resolution on 2x2 pixel blocks (space-to-depth): it also sees
    the current image folded that way, at full detail, so the difference and the mask can be
    as sharp as the image they change, at a quarter of a full-resolution convolution's cost.
    """

    def __init__(self, c: PredictionConfig):
        super().__init__()
        act = ACTIVATIONS[c.model.activation]
        layers: list[nn.Module] = [_conv(c.model.latent_channels, c.model.decoder_channels[0]), act()]
        width = c.model.decoder_channels[0]
        for w in c.model.decoder_channels[1:]:
            layers += [nn.Upsample(scale_factor=2, mode="nearest"), _conv(width, w), act()]
            width = w
        self.up = nn.Sequential(*layers)
        if c.model.latent_size * 2 ** len(c.model.decoder_channels) != c.model.image_size:
            raise ValueError("decoder_channels must upsample the latent grid to half the image size")
        self.full = nn.Sequential(_conv(width + 4 * c.model.channels, c.model.full_channels), act())
        k = c.outcomes.hypotheses
        # Forked in the latent, D decodes each candidate's own dc: one output per call.
        drawn = 1 if c.outcomes.fork == "latent" else k
        self.out = nn.Conv2d(c.model.full_channels, 4 * (c.model.channels + 1) * drawn, 1)
        with torch.no_grad():
            self.out.bias.view(drawn, c.model.channels + 1, 4)[:, -1] = (
                MASK_BIAS  # pixel_shuffle: channel-major
            )
        if k > 1:  # which candidate is likely, from each dc pooled over the grid (mean and max)
            self.choice = nn.Linear(2 * c.model.latent_channels * (k // drawn), k)
            nn.init.zeros_(self.choice.weight)
            nn.init.zeros_(self.choice.bias)

    def forward(self, dc: torch.Tensor, image: torch.Tensor) -> torch.Tensor:
        """(B, K * (C+1), H, W): each candidate's difference image, eq. (3)'s mask last."""
        x = torch.cat([self.up(dc), nn.functional.pixel_unshuffle(image, 2)], 1)
        return clamped_tanh(nn.functional.pixel_shuffle(self.out(self.full(x)), 2))

    def choice_logits(self, dc: torch.Tensor) -> torch.Tensor:
        """(B, K): how likely each candidate outcome is (softmax), for K > 1; dc (B, C, h, w),
        or (B, K, C, h, w) forked in the latent (every candidate's dc seen)."""
        return self.choice(torch.cat([dc.mean((-2, -1)), dc.amax((-2, -1))], -1).flatten(1))
