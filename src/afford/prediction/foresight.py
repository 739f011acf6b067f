"""Foresight: does the prediction net draw what an action does, to what it acts on and to the rest?

Table 2 (paper IV.B) averages the error over the image, where side effects are a few pixels of
a few steps. Foresight looks where they are. Every execution of a split is predicted one step
from its true state. Around each object concerned, disks of `effects.RADIUS_PX` pixels at its position
before and after the step; over those pixels

    foresight = 1 - (mean absolute error of the prediction) / (mean absolute error of copying the input)

so drawing the truth scores 1 and drawing nothing new scores 0 (below 0: worse than no change).
"Acted on" is the object the action grasps, places or turns; "side" the objects that took a
side effect (data/effects.py), per action type and per kind of effect.

The other way round, "still": the objects that neither were acted on nor took an effect, where
copying the input is right and any change drawn is an effect imagined; there the prediction's
mean absolute error itself is reported (a net that draws side effects everywhere scores well
on "side" and badly here).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import torch

from afford.data import effects as fx
from afford.data.effects import effect_mask, object_mask
from afford.data.format import Dataset
from afford.images import to_chw, to_hwc
from afford.sim.affordance import Col
from afford.sim.affordances import TYPES

BATCH = 32
PARTS = ("leaving", "landing")  # a side effect's disks: where objects were, where they ended


@dataclass
class Tally:
    """Sums over the pixels of one group: the prediction's and the copy's absolute errors."""

    predicted: float = 0.0
    copied: float = 0.0
    pixels: int = 0
    executions: int = 0

    def add(self, predicted: np.ndarray, copied: np.ndarray, mask: np.ndarray) -> None:
        if mask.any():
            self.predicted += float(predicted[mask].sum())
            self.copied += float(copied[mask].sum())
            self.pixels += int(mask.sum())
            self.executions += 1

    @property
    def foresight(self) -> float | None:
        return None if self.copied <= 0 else 1.0 - self.predicted / self.copied

    @property
    def error(self) -> float | None:
        """The prediction's mean absolute error per pixel (and channel) of the group."""
        return None if not self.pixels else self.predicted / self.pixels

    def as_dict(self) -> dict:
        value, error = self.foresight, self.error
        return {
            "foresight": None if value is None else round(value, 4),
            "error": None if error is None else round(error, 5),
            "executions": self.executions,
            "pixels": self.pixels,
        }


def pixel_errors(predicted: np.ndarray, truth: np.ndarray) -> np.ndarray:
    """(..., H, W) mean absolute error over the channels of (..., H, W, C) images."""
    return np.abs(predicted - truth).mean(-1)


def foresight_of(
    predicted: np.ndarray, before: np.ndarray, truth: np.ndarray, mask: np.ndarray
) -> float | None:
    """Foresight of one prediction over a mask (images (H, W, C))."""
    t = Tally()
    t.add(pixel_errors(predicted, truth), pixel_errors(before, truth), mask)
    return t.foresight


@dataclass
class Foresight:
    """Tallies by group: acted on / side, each overall and per type; side per kind."""

    acted: dict[str, Tally] = field(default_factory=lambda: {k: Tally() for k in ("all", *TYPES)})
    side: dict[str, Tally] = field(default_factory=lambda: {k: Tally() for k in ("all", *TYPES)})
    kinds: dict[str, Tally] = field(default_factory=lambda: {k: Tally() for k in fx.KINDS})
    # Side effects split by where: the disks objects leave from, and those they land in only.
    parts: dict[str, Tally] = field(default_factory=lambda: {k: Tally() for k in PARTS})
    still: dict[str, Tally] = field(default_factory=lambda: {k: Tally() for k in ("all", *TYPES)})

    def add(self, step: fx.StepEffects, action, before_poses, after_poses, predicted, before, truth) -> None:
        err, copy = pixel_errors(predicted, truth), pixel_errors(before, truth)
        if step.acted is not None:
            mask = object_mask(before_poses, after_poses, [step.acted])
            for key in ("all", step.type):
                self.acted[key].add(err, copy, mask)
        if step.effects:
            place = np.asarray(action[Col.POSITION], dtype=float)
            mask = fx.step_mask(step, before_poses, after_poses, action)
            for key in ("all", step.type):
                self.side[key].add(err, copy, mask)
            landing = fx.landing_mask(list(step.effects), before_poses, after_poses, place)
            self.parts["leaving"].add(err, copy, mask & ~landing)
            self.parts["landing"].add(err, copy, landing)
            for kind in step.kinds:
                of_kind = [e for e in step.effects if e.kind == kind]
                self.kinds[kind].add(err, copy, effect_mask(of_kind, before_poses, after_poses, place))
        concerned = {step.acted, *step.affected}
        still = [
            k for k in range(len(before_poses)) if k not in concerned and not np.isnan(before_poses[k, 0])
        ]
        mask = object_mask(before_poses, after_poses, still)
        if step.effects or step.acted is not None:  # keep the concerned objects' own pixels out
            mask &= ~object_mask(before_poses, after_poses, [k for k in concerned if k is not None])
        for key in ("all", step.type):
            self.still[key].add(err, copy, mask)

    def as_dict(self) -> dict:
        return {
            "acted": {k: t.as_dict() for k, t in self.acted.items()},
            "side": {k: t.as_dict() for k, t in self.side.items()},
            "kinds": {k: t.as_dict() for k, t in self.kinds.items()},
            "parts": {k: t.as_dict() for k, t in self.parts.items()},
            "still": {k: t.as_dict() for k, t in self.still.items()},
        }


@torch.no_grad()
def execution_batches(data: Dataset, split: str, limit: int | None = None, size: int = BATCH):
    """Every execution of a split (`limit`: the first so many sequences) in batches of `size`:
    lists of (its effect label, its sequence, its step index)."""
    batch: list[tuple] = []
    for i in list(data.indices(split))[:limit]:
        seq = data.sequence(i)
        for t, step in enumerate(fx.sequence_effects(seq)):
            batch.append((step, seq, t))
            if len(batch) == size:
                yield batch
                batch = []
    if batch:
        yield batch


def measure(predict, data: Dataset, split: str = "test", limit: int | None = None) -> Foresight:
    """Foresight of `predict(images (B, C, H, W), actions (B, 1, 7)) -> (B, 1, C, H, W)` over
    every execution of a split (`limit`: the first so many sequences)."""
    result = Foresight()
    for batch in execution_batches(data, split, limit):
        before = [seq.image(t) for _, seq, t in batch]
        actions = torch.from_numpy(np.stack([seq.actions[t] for _, seq, t in batch]))[:, None]
        predicted = to_hwc(predict(to_chw(np.stack(before)), actions)[:, 0])
        for (step, seq, t), image, pred in zip(batch, before, predicted, strict=True):
            result.add(step, seq.actions[t], seq.poses[t], seq.poses[t + 1], pred, image, seq.image(t + 1))
    return result


def format_foresight(result: dict) -> str:
    def cell(t: dict) -> str:
        return "-" if t["foresight"] is None else f"{t['foresight']:.2f} ({t['executions']})"

    groups = ("all", *TYPES)
    lines = [f"{'foresight (executions)':24s} " + " ".join(f"{g:>12s}" for g in groups)]
    for who in ("acted", "side"):
        name = "acted-on object" if who == "acted" else "side effects"
        lines.append(f"{name:24s} " + " ".join(f"{cell(result[who][g]):>12s}" for g in groups))
    lines.append("by kind: " + ", ".join(f"{k} {cell(t)}" for k, t in result["kinds"].items()))
    if "parts" in result:  # absent in results written before it was measured
        parts = ", ".join(f"{k} {cell(t)}" for k, t in result["parts"].items())
        lines.append(f"side effects, where: {parts}")
    if "still" in result:  # absent in results written before it was measured

        def error(t: dict) -> str:
            return "-" if t["error"] is None else f"{1000 * t['error']:.2f}"

        name = "still objects, error x1000"
        lines.append(f"{name:24s} " + " ".join(f"{error(result['still'][g]):>12s}" for g in groups))
    return "\n".join(lines)
