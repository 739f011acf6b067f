"""ROC AUC: how often a true clause scores above a false one."""

from __future__ import annotations

import numpy as np


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
