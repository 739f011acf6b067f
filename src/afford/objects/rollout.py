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
from afford.objects.perceive import perceive, slot_masks, to_state
from afford.objects.perception import PerceptionNet
from afford.objects.state import moved


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
        seen = perceive(self.perception, start)
        states = [to_state(objects) for objects in seen]
        masks = np.stack([slot_masks(objects) for objects in seen])  # (B, slots, H, W)
        as_seen = masks.any((2, 3))  # slots the image shows as seen: not yet moved
        poses = np.stack([p for p, _ in states])
        held = np.array([h for _, h in states])
        drawn = [self.drawer.render(poses[k], int(held[k])) for k in range(b)]
        image = list(start)
        out = np.zeros((b, length, *start.shape[1:]), np.float32)
        drawn_poses = np.zeros((b, length, *poses.shape[1:]), np.float32)
        for t in range(length):
            before = poses
            poses, held = self.dynamics.outcomes(poses, held, rows[:, t]).likeliest()
            go = moved(before, poses)
            poses = np.stack([self.drawer.rest(poses[k], int(held[k]), go[k]) for k in range(b)])
            drawn_poses[:, t] = poses
            for k in range(b):
                after = self.drawer.render(poses[k], int(held[k]))
                image[k] = self.drawer.draw(image[k], drawn[k], after, masks[k][go[k] & as_seen[k]].any(0))
                drawn[k] = after
                out[k, t] = image[k]
            as_seen &= ~go
        return to_chw(out), drawn_poses
