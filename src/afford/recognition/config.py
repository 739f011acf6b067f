"""Recognition net configuration, with the two presets (paper II.B, III.C)."""

from __future__ import annotations

from dataclasses import dataclass

from afford.sim.affordances import TYPES
from afford.sim.camera import SIZE


@dataclass(frozen=True)
class RecognitionConfig:
    # Architecture.
    in_channels: int = 4  # RGBD
    widths: tuple[int, ...] = (16, 32, 64, 128)  # channels at strides 2, 4, 8, 16
    depths: tuple[int, ...] = (1, 2, 2, 1)  # CSP bottlenecks per stage
    neck_depth: int = 1
    stride: int = 4  # the one detection layer: a 32x32 grid on 128x128 (the authors')
    anchors: tuple[float, ...] = (0.0, 90.0, 180.0, 270.0)  # angle anchors, degrees
    types: tuple[str, ...] = TYPES
    image_size: int = SIZE  # the camera's
    # Targets and losses. The confidence target at an assigned cell: 1 - conf_quality +
    # conf_quality * the quality of the cell's regression (targets.quality: Gaussians of its
    # position and angle errors, widths below); 0 keeps a plain 1.
    conf_quality: float = 0.0
    quality_cells: float = 0.6  # half of Table 1's 2.5 cm (4.9 px, 1.2 cells)
    quality_degrees: float = 2.5  # half of Table 1's 5 degrees
    neighbours: bool = True  # a target also goes to the 2 nearest neighbour cells (YOLO)
    z_scale: float = 10.0  # z (metres) is regressed as z * z_scale
    w_conf: float = 1.0
    w_type: float = 0.5
    w_xy: float = 1.0
    w_angle: float = 1.0
    w_z: float = 1.0
    w_sym: float = 0.5
    # Per type (in `types` order): the weight of an affordance's confidence, type and
    # regression terms. Turns are 4% of the affordances and the type recognised worst.
    type_weights: tuple[float, ...] = ()  # types not listed (all, here) weigh 1
    # Inference.
    confidence: float = 0.5  # default cut-off; `afford eval recognition` tunes it on val
    suppress_radius: float = 0.025  # metres: duplicates closer than this ...
    suppress_angle: float = 10.0  # ... and within this many degrees (any angle if symmetric)
    # Training.
    batch_size: int = 32
    lr: float = 2e-3
    weight_decay: float = 5e-4
    steps: int = 5000
    warmup: int = 200
    eval_every: int = 500
    log_every: int = 25
    shift_px: int = 4
    # With `afford train recognition --predicted FILE`: the share of each epoch's draws that are
    # predicted states (labelled by the true states' affordances), the rest true states.
    predicted_fraction: float = 0.5
    threads: int = 2
    # The random stream (draws, augmentation, initial weights); 0 is every shipped recipe's,
    # another measures how far two runs of one recipe differ.
    seed: int = 0

    @property
    def grid(self) -> int:
        return self.image_size // self.stride


PRESETS = {
    # 5,000 batches in 46.5 min on 2 CPU cores (see README). Turns weigh 3 (4% of the affordances), the
    # angle 4 (half the misses were angles off by more than Table 1's 5 degrees), and the
    # confidence learns the regression's quality: each measured in the README.
    "cpu": RecognitionConfig(w_angle=4.0, type_weights=(1.0, 1.0, 3.0), conf_quality=1.0),
    # The paper's widths: the default ScaledYOLOv4 (P5) halved.
    "paper": RecognitionConfig(
        widths=(32, 64, 128, 256),
        depths=(1, 3, 7, 3),
        neck_depth=2,
        batch_size=64,
        lr=1e-3,
        steps=100_000,
        eval_every=2000,
        log_every=100,
    ),
    # For tests: seconds per step.
    "tiny": RecognitionConfig(
        widths=(4, 8, 8, 8), depths=(1, 1, 1, 1), batch_size=4, steps=20, eval_every=10
    ),
}
