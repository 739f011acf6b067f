"""The measures the nets are judged by, in one place.

- The paper's Table 1 criteria (IV.A), recall per type and spurious detections per image: a
  true affordance is found when a detection of its type lies within 2.5 cm of it and within 5
  degrees of its angle (any angle when the true affordance is symmetric); a detection that
  finds no true affordance is spurious. Recognition on true and on predicted states uses them.
- ROC AUC: how often a true item scores above a false one (the agreement model's clauses, the
  prediction net's choice head).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from afford.sim.affordance import Detection
from afford.sim.affordances import TYPES, Affordance
from afford.sim.geometry import wrap180

MATCH_RADIUS = 0.025  # metres
MATCH_ANGLE = 5.0  # degrees


def matches(det: Affordance, true: Affordance) -> bool:
    if det.type != true.type:
        return False
    if np.linalg.norm(np.subtract(det.position, true.position)) > MATCH_RADIUS:
        return False
    return true.symmetric or abs(wrap180(det.angle - true.angle)) <= MATCH_ANGLE


@dataclass
class Tally:
    hits: dict[str, int] = field(default_factory=lambda: {t: 0 for t in TYPES})
    totals: dict[str, int] = field(default_factory=lambda: {t: 0 for t in TYPES})
    spurious: int = 0
    images: int = 0

    def add(self, detections: list[Detection], truths: list[Affordance]) -> None:
        self.images += 1
        for t in truths:
            self.totals[t.type] += 1
            if any(matches(d.affordance, t) for d in detections):
                self.hits[t.type] += 1
        self.spurious += sum(not any(matches(d.affordance, t) for t in truths) for d in detections)

    @property
    def recall(self) -> float:
        total = sum(self.totals.values())
        return sum(self.hits.values()) / total if total else 1.0

    @property
    def spurious_per_image(self) -> float:
        return self.spurious / max(self.images, 1)

    def table(self) -> dict:
        per = {
            t: {
                "hits": self.hits[t],
                "total": self.totals[t],
                "recall": self.hits[t] / max(self.totals[t], 1),
            }
            for t in TYPES
        }
        per["all"] = {
            "hits": sum(self.hits.values()),
            "total": sum(self.totals.values()),
            "recall": self.recall,
        }
        return {"images": self.images, "recall": per, "spurious_per_image": self.spurious_per_image}


def roc_auc(scores: np.ndarray, truths: np.ndarray) -> float:
    """The chance that a random true item scores above a random false one (ties count half);
    NaN when either class is missing. Ranks, so O(n log n)."""
    scores, truths = np.asarray(scores, dtype=float), np.asarray(truths).astype(bool)
    pos, neg = int(truths.sum()), int((~truths).sum())
    if pos == 0 or neg == 0:
        return float("nan")
    order = np.argsort(scores, kind="mergesort")
    ranks = np.empty(len(scores))
    ranks[order] = np.arange(1, len(scores) + 1)
    ordered = np.sort(scores)
    for value in np.unique(ordered[1:][np.diff(ordered) == 0]):  # tied scores share their mean rank
        tied = scores == value
        ranks[tied] = ranks[tied].mean()
    return float((ranks[truths].sum() - pos * (pos + 1) / 2) / (pos * neg))
