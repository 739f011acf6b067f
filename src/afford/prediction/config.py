"""Prediction pathway configuration (paper II.C; DESIGN.md), with its presets."""

from __future__ import annotations

from dataclasses import dataclass

from afford.sim.affordances import TYPES


@dataclass(frozen=True)
class PredictionConfig:
    # E and D (D mirrors E).
    channels: int = 4  # RGBD
    conv_channels: int = 8  # 2 convolutions, 3x3, stride 2: 128x128 -> 32x32x8 = 8192
    dense: tuple[int, ...] = (512,)  # dense layers between the 8192 conv features and the latent
    latent: int = 128
    image_size: int = 128
    # P^a modules, one per affordance type.
    types: tuple[str, ...] = TYPES
    p_layers: int = 10  # dense tanh layers, each 2 x latent wide (state half | memory half)
    pixel_input: bool = True  # the affordance pixel's RGBD in the action vector (Table 2 ablation)
    # Action vector normalisation: (position - centre) / scale, so its values are order 1.
    position_centre: tuple[float, float, float] = (0.0, 0.27, 0.05)
    position_scale: tuple[float, float, float] = (0.2, 0.2, 0.1)
    # Training.
    optimizer: str = "adam"  # "signsgd" as the paper, or "adam"
    lr: float = 1e-3
    batch_size: int = 32
    steps: int = 3000
    eval_every: int = 250
    log_every: int = 25
    patience: int = 5  # halve the lr after this many evaluations without improvement (paper)
    max_steps: int = 4  # executions per training run (1-4, random start)
    shift_px: int = 3
    mirror: bool = True
    angle_flip: bool = True
    position_noise: float = 0.002
    angle_noise: float = 1.0
    threads: int = 2

    @property
    def conv_size(self) -> int:
        return self.image_size // 4

    @property
    def conv_features(self) -> int:
        return self.conv_channels * self.conv_size**2

    @property
    def action_size(self) -> int:
        # x, y, z, angle (fraction of a turn), turn parameter (+-1, 0), the pixel's RGBD
        return 5 + self.channels


PRESETS = {
    # Smaller dense layers and a schedule of 3k batches: about an hour on 2 CPU cores. Adam,
    # because SignSGD at the paper's rate needs the paper's million batches.
    "cpu": PredictionConfig(),
    # The paper's sizes (II.C; the authors' public configuration for the P modules) and schedule.
    "paper": PredictionConfig(
        dense=(4096,),
        latent=128,
        optimizer="signsgd",
        lr=5e-5,
        steps=1_000_000,
        eval_every=10_000,
        log_every=500,
    ),
    "tiny": PredictionConfig(
        conv_channels=2, dense=(16,), latent=8, p_layers=2, batch_size=4, steps=20, eval_every=10, log_every=5
    ),
}
