"""A trained recognition net as a function: RGBD images -> affordance detections."""

from __future__ import annotations

import json
from dataclasses import asdict
from pathlib import Path

import numpy as np
import torch

from afford.images import to_chw
from afford.recognition.config import RecognitionConfig
from afford.recognition.model import RecognitionNet, fused_for_inference
from afford.recognition.targets import decode, suppress
from afford.sim.affordance import Detection
from afford.training.checkpoint import load_net_from_checkpoint

KIND = "recognition"
THRESHOLD_FILE = "threshold.json"  # written by `afford eval recognition` (tuned on val)


def read_threshold(run: str | Path) -> float | None:
    """The cut-off tuned on val for a training run (`afford eval recognition`), if any."""
    path = Path(run) / THRESHOLD_FILE
    return json.loads(path.read_text())["threshold"] if path.is_file() else None


def load_net(path: str | Path) -> tuple[RecognitionNet, RecognitionConfig, dict]:
    return load_net_from_checkpoint(path, KIND, RecognitionConfig, RecognitionNet)


def load_recognizer(path: str | Path) -> Recognizer:
    """The recognizer of a weights file or checkpoint, with its cut-off: the one export wrote
    into the file, else the one tuned for its training run (`read_threshold`), else the
    config's."""
    net, config, meta = load_net(path)
    threshold = meta.get("extra", {}).get("threshold")
    if threshold is None:
        threshold = read_threshold(Path(path).parent)
    return Recognizer(net, config, threshold)


class Recognizer:
    """Batched inference with the tuned cut-off and suppression (paper II.B)."""

    def __init__(self, net: RecognitionNet, config: RecognitionConfig, threshold: float | None = None):
        self.net = fused_for_inference(net.eval())
        self.config = config
        self.threshold = config.confidence if threshold is None else threshold

    @torch.no_grad()
    def raw(self, images: np.ndarray | torch.Tensor, batch_size: int = 256) -> torch.Tensor:
        """Head outputs for RGBD images in [0, 1]: NumPy (B, H, W, 4), or tensors (B, 4, H, W)
        as the prediction net gives them (afford/images.py)."""
        x = to_chw(images) if isinstance(images, np.ndarray) else images.float()
        return torch.cat([self.net(x[i : i + batch_size]) for i in range(0, len(x), batch_size)])

    def detections(self, raw: torch.Tensor, threshold: float | None = None) -> list[list[Detection]]:
        c = self.config
        t = self.threshold if threshold is None else threshold
        return [suppress(d, c.suppress_radius, c.suppress_angle) for d in decode(raw, c, t)]

    def __call__(self, images: np.ndarray | torch.Tensor, batch_size: int = 256) -> list[list[Detection]]:
        return self.detections(self.raw(images, batch_size))

    def describe(self) -> dict:
        return {"threshold": self.threshold, "config": asdict(self.config)}
