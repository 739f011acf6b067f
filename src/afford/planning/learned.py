"""The learned world model (paper II.D): recognise affordances in predicted futures.

Recognition runs on the root's real image and on every predicted image; prediction runs the
EM*D pathway. Each node keeps its latent, memory trace and predicted image, so a child costs
one P step and one D step. With `rerun_from_root` each child is instead predicted by running
the whole chain from the root image with the node's full plan, as the authors' planner does;
both give the same states (up to float rounding), the first is faster.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
import torch

from afford.data.format import encode_affordance
from afford.planning.tree import Node, Recognised
from afford.prediction.evaluate import load_net as load_prediction
from afford.prediction.model import PredictionNet
from afford.recognition.infer import Recognizer
from afford.sim.affordances import Affordance

WEIGHTS = Path(__file__).resolve().parent.parent / "weights"  # shipped with the package
RECOGNITION_FILE = "recognition.safetensors"
PREDICTION_FILE = "prediction.safetensors"


@dataclass
class LatentState:
    latent: torch.Tensor  # c_i: (latent,) for the dense net, (channels, 16, 16) for the spatial one
    memory: torch.Tensor  # the memory trace, shaped likewise


def find_weights(weights: str | Path | None = None) -> tuple[Path, Path]:
    """The recognition and prediction checkpoints in a folder (default: the shipped ones).

    A folder may also be a pair of training runs: recognition/ and prediction/ inside it, each
    with best.safetensors.
    """
    root = Path(weights) if weights else WEIGHTS
    flat = (root / RECOGNITION_FILE, root / PREDICTION_FILE)
    runs = (root / "recognition" / "best.safetensors", root / "prediction" / "best.safetensors")
    for rec, pred in (flat, runs):
        if rec.is_file() and pred.is_file():
            return rec, pred
    raise FileNotFoundError(
        f"{root}: no weights ({RECOGNITION_FILE} and {PREDICTION_FILE}, or recognition/ and "
        "prediction/ runs with best.safetensors)"
    )


class LearnedModel:
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
        images = image.permute(0, 2, 3, 1).numpy()
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
            images = image.permute(0, 2, 3, 1).numpy()
            for j, k in enumerate(ks):
                results[k] = (images[j], LatentState(latent[j], memory[j]))
        return [results[k] for k in range(len(parents))]


def recognise_nodes(recognizer: Recognizer, nodes: list[Node]) -> list[Recognised]:
    """The recognizer on each node's image: its affordances with their confidences."""
    detections = recognizer(np.stack([n.image for n in nodes]))
    return [[(d.affordance, d.score) for d in dets] for dets in detections]


def to_chw(images: np.ndarray) -> torch.Tensor:
    """(B, H, W, C) images as the nets' float32 (B, C, H, W) tensor."""
    return torch.from_numpy(np.ascontiguousarray(images, dtype=np.float32)).permute(0, 3, 1, 2)


@dataclass
class LearnedNets:
    """The trained nets of a weights folder."""

    recognizer: Recognizer  # with its tuned cut-off
    predictor: PredictionNet
    # The prediction nets of the ensemble planner (prediction/ensemble.py): the predictor
    # first, then the folder's ensemble/ members; just the predictor when it has none.
    members: tuple[PredictionNet, ...] = ()


def load_learned(weights: str | Path | None = None) -> LearnedNets:
    """The recognizer, the prediction net and the ensemble's members from a weights folder
    (default: the shipped one)."""
    import json

    from afford.prediction.ensemble import check_members, member_paths
    from afford.recognition.infer import THRESHOLD_FILE, load_net

    rec_path, pred_path = find_weights(weights)
    net, config, meta = load_net(rec_path)
    threshold = meta.get("extra", {}).get("threshold")  # set by `afford export`
    tuned = rec_path.parent / THRESHOLD_FILE
    if threshold is None and tuned.is_file():
        threshold = json.loads(tuned.read_text())["threshold"]
    predictor, _ = load_prediction(pred_path)
    members = [predictor] + [load_prediction(p)[0].eval() for p in member_paths(pred_path.parent)]
    check_members(members)
    return LearnedNets(Recognizer(net, config, threshold), predictor, tuple(members))
