"""The EM*D prediction pathway with differential prediction (paper II.C).

E encodes a state image to a latent c. For each action, the P module of its affordance type
turns (c, memory trace, action) into a latent difference dc and the next memory trace;
c' = c + dc (eq. 2). D decodes dc to an (n+1)-channel difference image whose last channel is a
mask, applied to the current image by eq. (3). The action vector's last values are the RGBD
of the affordance's pixel, read from the current image: the real one at the first step, the
predicted one after.

Two architectures fill in E, P^a and D (`config.architecture`): "dense", the paper's vector
latent (`dense.py`, the `paper` preset), and "spatial", a latent grid that learns on a CPU
(`spatial.py`, the `cpu` preset). This module holds what they share: routing by type, the
action vector, eq. (2) and (3), and the rollout.
"""

from __future__ import annotations

import torch
from torch import nn

from afford.prediction.config import PredictionConfig
from afford.prediction.dense import DenseDecoder, DenseEncoder, DenseP
from afford.prediction.layers import apply_difference, clamped_tanh, normalise_latent
from afford.prediction.spatial import SpatialDecoder, SpatialEncoder, SpatialP
from afford.sim.affordance import Col
from afford.sim.camera import world_to_pixel

__all__ = ["PredictionNet", "affordance_pixel", "apply_difference", "clamped_tanh", "normalise_latent"]

# architecture -> (E, P^a, D)
ARCHITECTURES: dict[str, tuple[type[nn.Module], type[nn.Module], type[nn.Module]]] = {
    "dense": (DenseEncoder, DenseP, DenseDecoder),
    "spatial": (SpatialEncoder, SpatialP, SpatialDecoder),
}


def affordance_pixel(images: torch.Tensor, positions: torch.Tensor) -> torch.Tensor:
    """RGBD (B, C) of the pixel each world position (B, 3) projects to (the camera model)."""
    px = world_to_pixel(positions).floor().long()
    col = px[:, 0].clamp(0, images.shape[-1] - 1)
    row = px[:, 1].clamp(0, images.shape[-2] - 1)
    return images[torch.arange(len(images), device=images.device), :, row, col]


class PredictionNet(nn.Module):
    def __init__(self, config: PredictionConfig):
        super().__init__()
        if config.architecture not in ARCHITECTURES:
            raise ValueError(
                f"unknown prediction architecture {config.architecture!r}; "
                f"expected one of {sorted(ARCHITECTURES)}"
            )
        encoder, p_module, decoder = ARCHITECTURES[config.architecture]
        self.config = config
        self.encoder = encoder(config)
        self.decoder = decoder(config)
        self.modules_by_type = nn.ModuleList(p_module(config) for _ in config.types)
        # Channels-last: the small convolutions over 128x128 images run ~3x faster on CPUs.
        self.to(memory_format=torch.channels_last) if config.architecture == "dense" else None
        self.register_buffer("pos_centre", torch.tensor(config.position_centre), persistent=False)
        self.register_buffer("pos_scale", torch.tensor(config.position_scale), persistent=False)

    def encode(self, image: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
        """E: (c_0, m_0) for images (B, C, H, W); the memory trace starts at zeros."""
        latent = self.encoder(image)
        return latent, self.encoder.initial_memory(latent)

    def action_vector(self, rows: torch.Tensor, image: torch.Tensor) -> torch.Tensor:
        """Affordance rows (B, 7: type, x, y, z, angle, symmetric, turn) -> the P input (B, 9)."""
        pos = rows[:, Col.POSITION]
        pixel = affordance_pixel(image, pos) if self.config.pixel_input else image.new_zeros(len(rows), 4)
        return torch.cat(
            [
                (pos - self.pos_centre) / self.pos_scale,
                (rows[:, Col.ANGLE, None] % 360.0) / 360.0,
                rows[:, Col.TURN, None] / 90.0,
                pixel,
            ],
            -1,
        )

    def step_with_difference(self, latent, memory, image, rows):
        """One prediction step, also returning D's difference image (B, C+1, H, W): eq. (3)'s
        new values and, last, its mask."""
        vector = self.action_vector(rows, image)
        pixel = world_to_pixel(rows[:, Col.POSITION])
        types = rows[:, Col.TYPE].long()
        dc = memory_out = None
        for t, module in enumerate(self.modules_by_type):
            idx = torch.nonzero(types == t).flatten()
            if not len(idx):
                continue
            d, m = module(latent[idx], memory[idx], vector[idx], pixel[idx])
            if dc is None:
                dc = latent.new_zeros((len(rows), *d.shape[1:]))
                memory_out = memory.new_zeros((len(rows), *m.shape[1:]))
            dc = dc.index_copy(0, idx, d)
            memory_out = memory_out.index_copy(0, idx, m)
        next_latent = self.encoder.renormalise(latent + dc)  # eq. (2)
        difference = self.decoder(dc, image)
        next_image = apply_difference(image, difference)  # eq. (3)
        return next_latent, memory_out, next_image, difference

    def step(self, latent, memory, image, rows):
        """One prediction: (c_i, m_i, s_i, a_i) -> (c_{i+1}, m_{i+1}, s_{i+1}).

        Each example goes through the P module of its own affordance type.
        """
        return self.step_with_difference(latent, memory, image, rows)[:3]

    def rollout_with_differences(
        self, image: torch.Tensor, actions: torch.Tensor, steps: torch.Tensor | None = None
    ) -> tuple[torch.Tensor, torch.Tensor]:
        """Predicted states (B, L, C, H, W) and D's differences (B, L, C+1, H, W) after each of
        L actions.

        With `steps` (B,), run k stops after steps[k] actions (its later outputs are zeros):
        padded steps of a batch cost nothing.
        """
        b, length = actions.shape[:2]
        at = image.device
        order = (
            torch.arange(b, device=at)
            if steps is None
            else torch.argsort(steps, descending=True, stable=True)
        )
        active = (
            torch.full((length,), b, device=at)
            if steps is None
            else (steps[order][None, :] > torch.arange(length, device=at)[:, None]).sum(1)
        )
        image = image[order]
        acts = actions[order]
        latent, memory = self.encode(image)
        states = differences = None
        for i in range(length):
            n = int(active[i])
            if n == 0:
                break
            latent, memory, image, difference = self.step_with_difference(
                latent[:n], memory[:n], image[:n], acts[:n, i]
            )
            if states is None:  # made here: under autocast the outputs may be bfloat16
                states = image.new_zeros((b, length, *image.shape[1:]))
                differences = difference.new_zeros((b, length, *difference.shape[1:]))
            states[order[:n], i] = image
            differences[order[:n], i] = difference
        return states, differences

    def forward(
        self, image: torch.Tensor, actions: torch.Tensor, steps: torch.Tensor | None = None
    ) -> tuple[torch.Tensor, torch.Tensor]:
        """Training's forward pass, `rollout_with_differences`: a call through the module, so
        that DistributedDataParallel sees it."""
        return self.rollout_with_differences(image, actions, steps)

    def rollout(
        self, image: torch.Tensor, actions: torch.Tensor, steps: torch.Tensor | None = None
    ) -> torch.Tensor:
        """Predicted states (B, L, C, H, W) after each of L actions (B, L, 7) from images (B, C, H, W)."""
        return self.rollout_with_differences(image, actions, steps)[0]
