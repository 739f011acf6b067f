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
from afford.prediction.rollout import Rollout

MEMBERS_DIR = "ensemble"  # in a weights folder: the members beside its prediction net


def spread(images: np.ndarray | torch.Tensor) -> np.ndarray:
    """Per-pixel spread of K members' images (K, ..., H, W, C) channels-last: the standard
    deviation over the members, mean over the channels -> (..., H, W). Zero where they agree."""
    x = np.asarray(images, dtype=np.float64)
    return x.std(axis=0).mean(axis=-1)


def total_variance(means: torch.Tensor, variances: torch.Tensor) -> torch.Tensor:
    """The variance of a state per pixel from K members' means (K, ..., C, H, W) and variances
    (K, ..., H, W): the mean of the variances plus the variance of the means (averaged over the
    channels), the law of total variance (as PETS, Chua et al. 2018). Zero where the members
    agree and are sure."""
    return variances.mean(0) + means.var(0, unbiased=False).mean(-3)


def outcome_variance(
    candidates: torch.Tensor, probability: torch.Tensor, drawn: torch.Tensor
) -> torch.Tensor:
    """Per pixel (..., H, W), the expected squared distance (averaged over the channels) of a
    net's K outcomes (..., K, C, H, W), weighed by their probabilities (..., K), from the image
    it drew (..., C, H, W): a two-outcome net's own variance, as the truth is each outcome with
    the head's probability. Zero when it is sure or its outcomes agree."""
    squared = ((candidates - drawn.unsqueeze(-4)) ** 2).mean(-3)
    return (probability[..., None, None] * squared).sum(-3)


def member_paths(folder: str | Path) -> list[Path]:
    """The members' checkpoints of a weights folder (FOLDER/ensemble/*.safetensors), sorted."""
    return sorted((Path(folder) / MEMBERS_DIR).glob("*.safetensors"))


def check_members(nets: list[PredictionNet]) -> None:
    """Members must agree on what they predict from: the same architecture and image size."""
    first = nets[0].config.model
    for k, net in enumerate(nets[1:], start=1):
        c = net.config.model
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
    """Per predicted state (a run's step): the members' spread and the ensemble mean's error,
    and the state's predicted variance (`total_variance`: the members' own outcome variances
    and their spread) against the mean's squared error."""

    spread: np.ndarray  # mean per-pixel spread (`spread`) over the image
    error: np.ndarray  # mean absolute RGBD error of the members' mean against the truth
    step: np.ndarray  # the step of the run it was predicted at (1-4)
    pixel_spread: np.ndarray  # per pixel, pooled over states (a sample): spread ...
    pixel_error: np.ndarray  # ... and the mean's absolute error there
    variance: np.ndarray  # mean predicted variance over the image (per channel value) ...
    squared: np.ndarray  # ... and the mean's squared error (mean over channels and pixels)
    pixel_variance: np.ndarray  # per sampled pixel: predicted variance ...
    pixel_squared: np.ndarray  # ... and the mean's squared error there

    def rank_correlation(self) -> float:
        """Spearman's rank correlation of spread and error over the states."""
        return spearman(self.spread, self.error)

    def ratio(self, scale: float = 1.0) -> float:
        """The spread-to-error ratio, sqrt(mean predicted variance / mean squared error): 1 when
        the variance says how large the error is; `scale` multiplies the variance first."""
        return float(np.sqrt(scale * self.variance.mean() / max(self.squared.mean(), 1e-12)))

    def fitted_scale(self) -> float:
        """The factor on the variance that makes the ratio 1 (fitted on val, used on test)."""
        return float(self.squared.mean() / max(self.variance.mean(), 1e-12))

    def variance_rank_correlation(self) -> float:
        """Spearman's rank correlation of predicted variance and squared error over the states."""
        return spearman(self.variance, self.squared)

    def reliability(self, bins: int = 8) -> list[dict]:
        """Sampled pixels in `bins` equal-count bins of predicted standard deviation: each bin's
        predicted and actual root mean squared error (equal where the variance is right)."""
        order = np.argsort(self.pixel_variance)
        return [
            {
                "predicted": float(np.sqrt(self.pixel_variance[part].mean())),
                "actual": float(np.sqrt(self.pixel_squared[part].mean())),
                "pixels": int(len(part)),
            }
            for part in np.array_split(order, bins)
        ]

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
    columns: dict[str, list] = {name: [] for name in ("spread", "error", "step", "variance", "squared")}
    pixels: dict[str, list] = {name: [] for name in ("spread", "error", "variance", "squared")}
    for b in range(0, len(picks), batch):
        images, actions, lengths = collate_prediction([runs[int(k)] for k in picks[b : b + batch]])
        outs, variances = [], []
        for m in members:
            rolled = m.rollout_hypotheses(images[:, 0], actions, lengths)
            outs.append(rolled.states)
            variances.append(member_variance(m, rolled, actions))
        outs = torch.stack(outs)  # (K, B, L, C, H, W)
        mean = outs.mean(0)
        per_pixel = {
            "spread": torch.from_numpy(
                spread(outs.permute(0, 1, 2, 4, 5, 3).numpy())
            ).float(),  # (B, L, H, W)
            "error": (mean - images[:, 1:]).abs().mean(2),
            "variance": total_variance(outs, torch.stack(variances)),
            "squared": ((mean - images[:, 1:]) ** 2).mean(2),
        }
        for j in range(len(lengths)):
            for s in range(int(lengths[j])):
                at = rng.integers(per_pixel["spread"][j, s].numel(), size=PIXELS_PER_STATE)
                for name, values in per_pixel.items():
                    columns[name].append(float(values[j, s].mean()))
                    pixels[name].append(values[j, s].flatten()[at].numpy())
                columns["step"].append(s + 1)
    return Calibration(
        **{name: np.array(values) for name, values in columns.items()},
        **{f"pixel_{name}": np.concatenate(values) for name, values in pixels.items()},
    )


def member_variance(net: PredictionNet, rolled: Rollout, actions: torch.Tensor) -> torch.Tensor:
    """A member's own variance per pixel of each state it rolled out (B, L, H, W), from its
    `rollout_hypotheses` of `actions` (B, L, 7): for a net with a side-effect outcome, the
    spread of its outcomes about the one it drew (`outcome_variance`); zero for one outcome."""
    states, candidates, logits = rolled.states, rolled.candidates, rolled.logits
    if candidates is None or net.config.outcomes.hypotheses_by != "effect":
        return torch.zeros_like(states[:, :, 0])
    b, length = logits.shape[:2]
    probability = net.probabilities(logits.flatten(0, 1), actions.flatten(0, 1)).view(b, length, -1)
    return outcome_variance(candidates, probability, states)
