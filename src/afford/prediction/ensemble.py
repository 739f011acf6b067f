"""An ensemble of prediction nets, and the spread of what they predict (paper V).

Section V asks for "a more principled approach" to actions whose outcome is uncertain. The
members are EM*D nets of one architecture that were trained apart (different data orders
and bootstrap resamples of the training sequences, `--set seed=K --set bootstrap=true`):
where the data pins an outcome down they agree; where it hangs on details the images cannot
settle (a place near a tipping edge) they part. Each member rolls out its own chain of
latents, memory traces and images, so a plan's predicted outcome is K images, and their
spread is the planner's measure of how sure it may be of that outcome.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
import torch

from afford.prediction.model import PredictionNet

MEMBERS_DIR = "ensemble"  # in a weights folder: the members beside its prediction net


def spread(images: np.ndarray | torch.Tensor) -> np.ndarray:
    """Per-pixel spread of K members' images (K, ..., H, W, C) channels-last: the standard
    deviation over the members, mean over the channels -> (..., H, W). Zero where they agree."""
    x = np.asarray(images, dtype=np.float64)
    return x.std(axis=0).mean(axis=-1)


def member_paths(folder: str | Path) -> list[Path]:
    """The members' checkpoints of a weights folder (FOLDER/ensemble/*.safetensors), sorted."""
    return sorted((Path(folder) / MEMBERS_DIR).glob("*.safetensors"))


def check_members(nets: list[PredictionNet]) -> None:
    """Members must agree on what they predict from: the same architecture and image size."""
    first = nets[0].config
    for k, net in enumerate(nets[1:], start=1):
        c = net.config
        if (c.architecture, c.image_size, c.channels, c.types) != (
            first.architecture,
            first.image_size,
            first.channels,
            first.types,
        ):
            raise ValueError(
                f"ensemble member {k} is a {c.architecture} net unlike member 0 ({first.architecture})"
            )


@dataclass
class Calibration:
    """Per predicted state (a run's step): the members' spread and the ensemble mean's error."""

    spread: np.ndarray  # mean per-pixel spread (`spread`) over the image
    error: np.ndarray  # mean absolute RGBD error of the members' mean against the truth
    step: np.ndarray  # the step of the run it was predicted at (1-4)
    pixel_spread: np.ndarray  # per pixel, pooled over states (a sample): spread ...
    pixel_error: np.ndarray  # ... and the mean's absolute error there

    def rank_correlation(self) -> float:
        """Spearman's rank correlation of spread and error over the states."""
        return spearman(self.spread, self.error)

    def by_spread(self, bins: int = 5) -> list[dict]:
        """States split into `bins` equal-count bins of spread: each bin's spread and error."""
        order = np.argsort(self.spread)
        return [
            {
                "spread": float(self.spread[part].mean()),
                "error": float(self.error[part].mean()),
                "states": int(len(part)),
            }
            for part in np.array_split(order, bins)
        ]


def spearman(a: np.ndarray, b: np.ndarray) -> float:
    ra, rb = np.argsort(np.argsort(a)), np.argsort(np.argsort(b))
    return float(np.corrcoef(ra, rb)[0, 1])


PIXELS_PER_STATE = 64  # pixels sampled from each state for the per-pixel calibration


@torch.no_grad()
def calibrate(members, data, split: str = "test", limit: int | None = None, batch: int = 16) -> Calibration:
    """Every member rolls out the split's runs from their first state through all their
    executions (as Table 2 is measured); per predicted state, the spread and the mean's error."""
    from afford.data.torch_data import PredictionData, collate_prediction

    runs = PredictionData(data, split, max_steps=4, random_start=False)
    picks = np.arange(len(runs)) if limit is None else np.linspace(0, len(runs) - 1, limit).astype(int)
    rng = np.random.default_rng(0)
    spreads, errors, steps, px_s, px_e = [], [], [], [], []
    for b in range(0, len(picks), batch):
        images, actions, lengths = collate_prediction([runs[int(k)] for k in picks[b : b + batch]])
        outs = torch.stack([m.rollout(images[:, 0], actions, lengths) for m in members])  # (K, B, L, C, H, W)
        mean = outs.mean(0)
        per_pixel = torch.from_numpy(spread(outs.permute(0, 1, 2, 4, 5, 3).numpy())).float()  # (B, L, H, W)
        err = (mean - images[:, 1:]).abs().mean(2)
        for j in range(len(lengths)):
            for s in range(int(lengths[j])):
                spreads.append(float(per_pixel[j, s].mean()))
                errors.append(float(err[j, s].mean()))
                steps.append(s + 1)
                at = rng.integers(per_pixel[j, s].numel(), size=PIXELS_PER_STATE)
                px_s.append(per_pixel[j, s].flatten()[at].numpy())
                px_e.append(err[j, s].flatten()[at].numpy())
    return Calibration(
        np.array(spreads), np.array(errors), np.array(steps), np.concatenate(px_s), np.concatenate(px_e)
    )
