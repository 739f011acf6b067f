"""The one boundary between the two layouts an image takes.

On the NumPy side (the simulator's renders, the dataset, the planner's nodes, the goal patch,
the pictures) an image is (..., H, W, C) float32 RGBD in [0, 1]; the nets take and give torch
tensors (..., C, H, W). These two functions are the only crossings: a NumPy image is always
channels-last and a tensor always channels-first, so nothing needs to guess from a shape.
"""

from __future__ import annotations

import numpy as np
import torch


def to_chw(images: np.ndarray) -> torch.Tensor:
    """NumPy (..., H, W, C) -> a float32 tensor (..., C, H, W) for the nets."""
    images = np.ascontiguousarray(images, dtype=np.float32)
    return torch.from_numpy(np.ascontiguousarray(np.moveaxis(images, -1, -3)))


def to_hwc(images: torch.Tensor) -> np.ndarray:
    """A tensor (..., C, H, W) from the nets -> NumPy (..., H, W, C) float32."""
    return np.ascontiguousarray(images.detach().float().cpu().movedim(-3, -1).numpy())
