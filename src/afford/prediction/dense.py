"""The `paper` preset's E, P^a and D: the paper's dense latent (II.C, Fig. 4).

E: 2 convolutions (3x3, stride 2) to 32 x 32 x 8 = 8192 features, dense layers, a latent
normalised as a / sqrt(1 + sum a^2). P^a: dense tanh layers of [state half | memory half], the
action vector fed to each, a residual on the state half, the memory half handed to the next
step (the authors' configuration). D mirrors E, with 2x nearest upsampling between its
up-convolutions. tanh everywhere, D's output clamped to [0, 1].
"""

from __future__ import annotations

import torch
from torch import nn

from afford.prediction.config import PredictionConfig
from afford.prediction.layers import clamped_tanh, normalise_latent

# D's mask starts a little open (clamped tanh(0.15) = 0.15): fully closed, neither the mask nor
# the difference image would get a gradient (eq. 3 multiplies one by the other).
MASK_BIAS = 0.15


class DenseEncoder(nn.Module):
    def __init__(self, c: PredictionConfig):
        super().__init__()
        k = c.model.conv_channels
        self.convs = nn.Sequential(
            nn.Conv2d(c.model.channels, k, 3, 2, 1), nn.Tanh(), nn.Conv2d(k, k, 3, 2, 1), nn.Tanh()
        )
        sizes = [c.model.conv_features, *c.model.dense, c.model.latent]
        layers: list[nn.Module] = []
        for i, (a, b) in enumerate(zip(sizes[:-1], sizes[1:], strict=True)):
            layers.append(nn.Linear(a, b))
            if i < len(sizes) - 2:
                layers.append(nn.Tanh())
        self.dense = nn.Sequential(*layers)

    def forward(self, image: torch.Tensor) -> torch.Tensor:
        features = self.convs(image.contiguous(memory_format=torch.channels_last))
        return normalise_latent(self.dense(features.contiguous().flatten(1)))

    def initial_memory(self, latent: torch.Tensor) -> torch.Tensor:
        return torch.zeros_like(latent)  # no trace before the first step

    def renormalise(self, latent: torch.Tensor) -> torch.Tensor:
        return normalise_latent(latent)  # the authors re-normalise after eq. (2)


class DenseDecoder(nn.Module):
    """Latent difference -> (n+1)-channel difference image, every channel in [0, 1]."""

    def __init__(self, c: PredictionConfig):
        super().__init__()
        sizes = [c.model.latent, *reversed(c.model.dense), c.model.conv_features]
        layers: list[nn.Module] = []
        for a, b in zip(sizes[:-1], sizes[1:], strict=True):
            layers += [nn.Linear(a, b), nn.Tanh()]
        self.dense = nn.Sequential(*layers)
        self.shape = (c.model.conv_channels, c.model.conv_size, c.model.conv_size)
        k = c.model.conv_channels
        # Nearest-neighbour 2x upscaling between the up-convolutions (paper, after [25]).
        self.up = nn.Sequential(
            nn.Upsample(scale_factor=2, mode="nearest"),
            nn.Conv2d(k, k, 3, 1, 1),
            nn.Tanh(),
            nn.Upsample(scale_factor=2, mode="nearest"),
            nn.Conv2d(k, c.model.channels + 1, 3, 1, 1),
        )
        with torch.no_grad():
            self.up[-1].bias[-1] = MASK_BIAS

    def forward(self, dc: torch.Tensor, image: torch.Tensor) -> torch.Tensor:
        x = self.dense(dc).view(-1, *self.shape).contiguous(memory_format=torch.channels_last)
        return clamped_tanh(self.up(x))


class DenseP(nn.Module):
    """One affordance type's prediction module (Fig. 4, the authors' configuration).

    Each layer sees [state half | memory half | action]; the state half is carried by a
    residual from layer to layer, the memory half becomes the next step's memory trace.
    """

    def __init__(self, c: PredictionConfig):
        super().__init__()
        width = 2 * c.model.latent
        self.latent = c.model.latent
        self.layers = nn.ModuleList(
            nn.Linear(width + c.model.action_size, width) for _ in range(c.model.p_layers)
        )

    def forward(self, latent: torch.Tensor, memory: torch.Tensor, vector: torch.Tensor, pixel: torch.Tensor):
        h = torch.cat([latent, memory], -1)
        for layer in self.layers:
            out = torch.tanh(layer(torch.cat([h, vector], -1)))
            h = torch.cat([h[:, : self.latent] + out[:, : self.latent], out[:, self.latent :]], -1)
        return h[:, : self.latent] - latent, h[:, self.latent :]
