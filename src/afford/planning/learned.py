"""The learned world model (paper II.D): recognise affordances in predicted futures.

Recognition runs on the root's real image and on every predicted image; prediction runs the
EM*D pathway. Each node keeps its latent, memory trace and predicted image, so a child costs
one P step and one D step. With `rerun_from_root` each child is instead predicted by running
the whole chain from the root image with the node's full plan, as the authors' planner does;
both give the same states (up to float rounding), the first is faster.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import torch

from afford.images import to_chw, to_hwc
from afford.planning.tree import Node, Recognised, WorldModel
from afford.prediction.model import PredictionNet
from afford.recognition.infer import Recognizer
from afford.sim.affordance import encode_affordance
from afford.sim.affordances import Affordance


@dataclass
class LatentState:
    latent: torch.Tensor  # c_i: (latent,) for the dense net, (channels, 16, 16) for the spatial one
    memory: torch.Tensor  # the memory trace, shaped likewise


class LearnedModel(WorldModel):
    """A `WorldModel` of the trained nets, started from the real RGBD image the caller gives
    (it needs no simulator: only the camera's view of the start)."""

    def __init__(
        self,
        image: np.ndarray,
        recognizer: Recognizer,
        predictor: PredictionNet,
        rerun_from_root: bool = False,
    ):
        self.image = np.asarray(image, dtype=np.float32)
        self.recognizer = recognizer
        self.net = predictor.eval()
        self.rerun_from_root = rerun_from_root
        self.p_steps = 0  # P+D steps run, for the benchmark of keeping latents

    @torch.no_grad()
    def root(self):
        latent, memory = self.net.encode(to_chw(self.image[None]))
        return self.image, LatentState(latent[0], memory[0])

    def recognise(self, nodes: list[Node]) -> list[Recognised]:
        return recognise_nodes(self.recognizer, nodes)

    @torch.no_grad()
    def predict(self, parents: list[Node], actions: list[Affordance]):
        if self.rerun_from_root:
            return self._predict_from_root(parents, actions)
        rows = torch.from_numpy(np.stack([encode_affordance(a) for a in actions]))
        latent = torch.stack([p.state.latent for p in parents])
        memory = torch.stack([p.state.memory for p in parents])
        image = to_chw(np.stack([p.image for p in parents]))
        latent, memory, image = self.net.step(latent, memory, image, rows)
        self.p_steps += len(parents)
        images = to_hwc(image)
        return [(images[k], LatentState(latent[k], memory[k])) for k in range(len(parents))]

    def _predict_from_root(self, parents: list[Node], actions: list[Affordance]):
        by_depth: dict[int, list[int]] = {}
        for k, p in enumerate(parents):
            by_depth.setdefault(p.depth, []).append(k)
        results: dict[int, tuple] = {}
        for depth, ks in by_depth.items():
            plans = [list(parents[k].plan) + [actions[k]] for k in ks]
            rows = torch.from_numpy(np.stack([[encode_affordance(a) for a in plan] for plan in plans]))
            root = to_chw(np.stack([self.image] * len(ks)))
            latent, memory = self.net.encode(root)
            image = root
            for i in range(depth + 1):
                latent, memory, image = self.net.step(latent, memory, image, rows[:, i])
            self.p_steps += len(ks) * (depth + 1)
            images = to_hwc(image)
            for j, k in enumerate(ks):
                results[k] = (images[j], LatentState(latent[j], memory[j]))
        return [results[k] for k in range(len(parents))]


def recognise_nodes(recognizer: Recognizer, nodes: list[Node]) -> list[Recognised]:
    """The recognizer on each node's image: its detections (affordances with confidences)."""
    return recognizer(np.stack([n.image for n in nodes]))
