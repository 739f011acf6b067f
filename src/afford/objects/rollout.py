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
from afford.objects.dynamics import ObjectDynamics, predict
from afford.objects.perceive import perceive, to_state
from afford.objects.perception import PerceptionNet


class ObjectRollout:
    def __init__(self, perception: PerceptionNet, dynamics: ObjectDynamics, drawer: Drawer | None = None):
        self.perception, self.dynamics = perception, dynamics
        self.drawer = drawer if drawer is not None else Drawer()

    @torch.no_grad()
    def rollout(self, images: torch.Tensor, actions: torch.Tensor, steps=None) -> torch.Tensor:
        start = to_hwc(images)
        rows = actions.numpy()
        b, length = rows.shape[:2]
        states = [to_state(objects) for objects in perceive(self.perception, start)]
        poses = np.stack([p for p, _ in states])
        held = np.array([h for _, h in states])
        drawn = [self.drawer.render(poses[k], int(held[k])) for k in range(b)]
        image = list(start)
        out = np.zeros((b, length, *start.shape[1:]), np.float32)
        for t in range(length):
            poses, held = predict(self.dynamics, poses, held, rows[:, t]).likeliest()
            for k in range(b):
                after = self.drawer.render(poses[k], int(held[k]))
                image[k] = self.drawer.draw(image[k], drawn[k], after)
                drawn[k] = after
                out[k, t] = image[k]
        return to_chw(out)
