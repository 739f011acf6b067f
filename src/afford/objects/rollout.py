"""The object world model rolled out like a prediction net, so that the paper's measures of a
prediction net (Table 2, foresight, recognition on predicted states) measure it the same way.

`rollout(images, actions, steps)` takes and returns what `PredictionNet.rollout` does: start
images (B, 4, H, W) and affordance rows (B, L, 7), the predicted images (B, L, 4, H, W). The
start is perceived once; then each step moves the objects (the likeliest outcome) and draws
the next image from the last one.
"""

from __future__ import annotations

import numpy as np
import torch

from afford.images import to_chw, to_hwc
from afford.objects.draw import Drawer
from afford.objects.dynamics import ObjectDynamics
from afford.objects.perception import PerceptionNet
from afford.objects.world import perceived, step


class ObjectRollout:
    def __init__(self, perception: PerceptionNet, dynamics: ObjectDynamics, drawer: Drawer | None = None):
        self.perception, self.dynamics = perception, dynamics
        self.drawer = drawer if drawer is not None else Drawer()

    def rollout(self, images: torch.Tensor, actions: torch.Tensor, steps=None) -> torch.Tensor:
        return self.roll(images, actions)[0]

    @torch.no_grad()
    def roll(self, images: torch.Tensor, actions: torch.Tensor) -> tuple[torch.Tensor, np.ndarray]:
        """The predicted images (B, L, 4, H, W), and the objects drawn in them: pose rows
        (B, L, slots, 7) in the slots perception filled (NaN: none)."""
        start = to_hwc(images)
        rows = actions.numpy()
        b, length = rows.shape[:2]
        states = perceived(self.perception, self.drawer, start)
        image = list(start)
        out = np.zeros((b, length, *start.shape[1:]), np.float32)
        drawn_poses = np.zeros((b, length, *states[0].poses.shape), np.float32)
        for t in range(length):
            poses = np.stack([s.poses for s in states])
            held = np.array([s.held for s in states])
            poses, held = self.dynamics.outcomes(poses, held, rows[:, t]).likeliest()
            for k in range(b):
                image[k], states[k] = step(self.drawer, image[k], states[k], poses[k], int(held[k]))
                drawn_poses[k, t] = states[k].poses
                out[k, t] = image[k]
        return to_chw(out), drawn_poses
