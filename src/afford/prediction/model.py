"""The EM*D prediction pathway with differential prediction (paper II.C, Fig. 4).

E encodes a state image to a latent c. For each action, the P module of its affordance type
turns (c, memory trace, action vector) into a latent difference dc and the next memory trace;
c' = c + dc (eq. 2). D decodes dc to an (n+1)-channel difference image whose last channel is a
mask, applied to the current image by eq. (3). The action vector's last values are the RGBD
of the affordance's pixel, read from the current image: the real one at the first step, the
predicted one after.
"""

from __future__ import annotations

import torch
from torch import nn

from afford.prediction.config import PredictionConfig
from afford.sim.camera import FOCAL_PX, SIZE
from afford.sim.constants import CAMERA

# D's mask starts a little open (clamped tanh(0.15) = 0.15): fully closed, neither the mask nor
# the difference image would get a gradient (eq. 3 multiplies one by the other).
MASK_BIAS = 0.15


def normalise_latent(a: torch.Tensor) -> torch.Tensor:
    """The authors' latent normalisation: a / sqrt(1 + sum a^2), keeping the norm below 1."""
    return a / torch.sqrt(1 + (a * a).sum(-1, keepdim=True))


def clamped_tanh(x: torch.Tensor) -> torch.Tensor:
    """tanh clamped to [0, 1] (the authors' D output), with tanh's gradient through the clamp.

    The clamp lets the mask be exactly 0, so eq. (3) copies unchanged pixels exactly; passing
    the gradient straight through it keeps a closed mask able to open again where a change
    appears (a plain clamp would leave it dead).
    """
    t = torch.tanh(x)
    return t + (t.clamp(0.0, 1.0) - t).detach()


class Encoder(nn.Module):
    def __init__(self, c: PredictionConfig):
        super().__init__()
        k = c.conv_channels
        self.convs = nn.Sequential(
            nn.Conv2d(c.channels, k, 3, 2, 1), nn.Tanh(), nn.Conv2d(k, k, 3, 2, 1), nn.Tanh(), nn.Flatten()
        )
        sizes = [c.conv_features, *c.dense, c.latent]
        layers: list[nn.Module] = []
        for i, (a, b) in enumerate(zip(sizes[:-1], sizes[1:], strict=True)):
            layers.append(nn.Linear(a, b))
            if i < len(sizes) - 2:
                layers.append(nn.Tanh())
        self.dense = nn.Sequential(*layers)

    def forward(self, image: torch.Tensor) -> torch.Tensor:
        features = self.convs[:-1](image.contiguous(memory_format=torch.channels_last))
        return normalise_latent(self.dense(features.contiguous().flatten(1)))


class Decoder(nn.Module):
    """Latent difference -> (n+1)-channel difference image, every channel in [0, 1]."""

    def __init__(self, c: PredictionConfig):
        super().__init__()
        sizes = [c.latent, *reversed(c.dense), c.conv_features]
        layers: list[nn.Module] = []
        for a, b in zip(sizes[:-1], sizes[1:], strict=True):
            layers += [nn.Linear(a, b), nn.Tanh()]
        self.dense = nn.Sequential(*layers)
        self.shape = (c.conv_channels, c.conv_size, c.conv_size)
        k = c.conv_channels
        # Nearest-neighbour 2x upscaling between the up-convolutions (paper, after [25]).
        self.up = nn.Sequential(
            nn.Upsample(scale_factor=2, mode="nearest"),
            nn.Conv2d(k, k, 3, 1, 1),
            nn.Tanh(),
            nn.Upsample(scale_factor=2, mode="nearest"),
            nn.Conv2d(k, c.channels + 1, 3, 1, 1),
        )
        with torch.no_grad():
            self.up[-1].bias[-1] = MASK_BIAS

    def forward(self, dc: torch.Tensor) -> torch.Tensor:
        x = self.dense(dc).view(-1, *self.shape).contiguous(memory_format=torch.channels_last)
        return clamped_tanh(self.up(x))


class PModule(nn.Module):
    """One affordance type's prediction module (Fig. 4, the authors' configuration).

    Each layer sees [state half | memory half | action]; the state half is carried by a
    residual from layer to layer, the memory half becomes the next step's memory trace.
    """

    def __init__(self, c: PredictionConfig):
        super().__init__()
        width = 2 * c.latent
        self.latent = c.latent
        self.layers = nn.ModuleList(nn.Linear(width + c.action_size, width) for _ in range(c.p_layers))

    def forward(self, latent: torch.Tensor, memory: torch.Tensor, action: torch.Tensor):
        h = torch.cat([latent, memory], -1)
        for layer in self.layers:
            out = torch.tanh(layer(torch.cat([h, action], -1)))
            h = torch.cat([h[:, : self.latent] + out[:, : self.latent], out[:, self.latent :]], -1)
        return h[:, : self.latent] - latent, h[:, self.latent :]


def apply_difference(state: torch.Tensor, difference: torch.Tensor) -> torch.Tensor:
    """Eq. (3): s_{i+1} = mask * diff + (1 - mask) * s_i, the mask being the last channel."""
    mask = difference[:, -1:]
    return mask * difference[:, :-1] + (1 - mask) * state


def affordance_pixel(images: torch.Tensor, positions: torch.Tensor) -> torch.Tensor:
    """RGBD (B, C) of the pixel each world position (B, 3) projects to (the camera model)."""
    cx, cy, cz = CAMERA.pos
    depth = cz - positions[:, 2]
    col = SIZE / 2 + FOCAL_PX * (positions[:, 0] - cx) / depth
    row = SIZE / 2 - FOCAL_PX * (positions[:, 1] - cy) / depth
    col = col.floor().long().clamp(0, images.shape[-1] - 1)
    row = row.floor().long().clamp(0, images.shape[-2] - 1)
    return images[torch.arange(len(images)), :, row, col]


class PredictionNet(nn.Module):
    def __init__(self, config: PredictionConfig):
        super().__init__()
        self.config = config
        self.encoder = Encoder(config)
        self.decoder = Decoder(config)
        self.modules_by_type = nn.ModuleList(PModule(config) for _ in config.types)
        # Channels-last: the small convolutions over 128x128 images run ~3x faster on CPUs.
        self.to(memory_format=torch.channels_last)
        self.register_buffer("pos_centre", torch.tensor(config.position_centre), persistent=False)
        self.register_buffer("pos_scale", torch.tensor(config.position_scale), persistent=False)

    def action_vector(self, rows: torch.Tensor, image: torch.Tensor) -> torch.Tensor:
        """Affordance rows (B, 7: type, x, y, z, angle, symmetric, turn) -> the P input (B, 9)."""
        pos = rows[:, 1:4]
        pixel = affordance_pixel(image, pos) if self.config.pixel_input else image.new_zeros(len(rows), 4)
        return torch.cat(
            [
                (pos - self.pos_centre) / self.pos_scale,
                (rows[:, 4:5] % 360.0) / 360.0,
                rows[:, 6:7] / 90.0,
                pixel,
            ],
            -1,
        )

    def step(self, latent, memory, image, rows):
        """One prediction: (c_i, m_i, s_i, a_i) -> (c_{i+1}, m_{i+1}, s_{i+1}).

        Each example goes through the P module of its own affordance type.
        """
        action = self.action_vector(rows, image)
        types = rows[:, 0].long()
        dc = torch.zeros_like(latent)
        new_memory = torch.zeros_like(memory)
        for t, module in enumerate(self.modules_by_type):
            idx = torch.nonzero(types == t).flatten()
            if len(idx):
                d, m = module(latent[idx], memory[idx], action[idx])
                dc = dc.index_copy(0, idx, d)
                new_memory = new_memory.index_copy(0, idx, m)
        next_latent = normalise_latent(latent + dc)  # eq. (2), re-normalised
        next_image = apply_difference(image, self.decoder(dc))  # eq. (3)
        return next_latent, new_memory, next_image

    def rollout(self, image: torch.Tensor, actions: torch.Tensor) -> torch.Tensor:
        """Predicted states (B, L, C, H, W) after each of L actions (B, L, 7) from images (B, C, H, W)."""
        latent = self.encoder(image)
        memory = torch.zeros_like(latent)  # no trace before the first step
        out = []
        for i in range(actions.shape[1]):
            latent, memory, image = self.step(latent, memory, image, actions[:, i])
            out.append(image)
        return torch.stack(out, 1)
