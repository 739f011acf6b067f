"""How likely a side effect is: the choice head of a two-outcome net, measured and calibrated.

A net with a canonical and a side-effect outcome per step (`hypotheses_by="effect"`) has a head
that says how likely the side effect is. Training draws runs with side effects more often than
they come (`effect_fraction`), so the raw head overstates them: on val the shipped net's mean
probability was 0.18 where 0.12 of the executions had one. A planner that weighs outcomes by
their probability (planning/branches.py) needs them as they come, so the head's logit (the
side effect's minus the canonical one's) is read through Platt scaling, sigmoid(a z + b), with
a and b fitted on val by maximum likelihood; the net's config keeps them (`choice_scale`,
`choice_bias`) and `PredictionNet.probabilities` applies them.

Measured per execution from the true state before it, as foresight is (prediction/foresight.py),
against the label of data/effects.py: did anything but the canonical effect follow.
"""

from __future__ import annotations

import json
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np
import torch

from afford.data.format import Dataset
from afford.images import to_chw
from afford.metrics import roc_auc
from afford.prediction.foresight import execution_batches
from afford.prediction.model import PredictionNet
from afford.sim.affordance import Col
from afford.sim.affordances import TYPES

CALIBRATION_FILE = "calibration.json"  # in a training run, written by `afford eval prediction`
BATCH = 64
NEWTON_STEPS = 50


@dataclass
class HeadReport:
    """The head on one split: executions, the share with a side effect, the mean probability
    the head gives (raw and calibrated), their log-loss, and the ROC AUC (calibration leaves it)."""

    executions: int
    rate: float
    mean_raw: float
    mean_calibrated: float
    nll_raw: float
    nll_calibrated: float
    auc: float


@torch.no_grad()
def head_logits(net: PredictionNet, data: Dataset, split: str, limit: int | None = None):
    """(z, labels, kinds): the head's side-effect logit for every execution of a split, whether
    a side effect followed, and the action's type (its index in sim.affordances.TYPES)."""
    z: list[float] = []
    labels: list[bool] = []
    kinds: list[int] = []
    for batch in execution_batches(data, split, limit, BATCH):
        images = to_chw(np.stack([seq.image(t) for _, seq, t in batch]))
        actions = torch.from_numpy(np.stack([seq.actions[t] for _, seq, t in batch]))[:, None]
        logits = net.rollout_hypotheses(images, actions).logits
        z.extend((logits[:, 0, 1] - logits[:, 0, 0]).float().tolist())
        labels.extend(not step.canonical for step, _, _ in batch)
        kinds.extend(actions[:, 0, Col.TYPE].long().tolist())
    return np.array(z), np.array(labels), np.array(kinds)


def fit_per_type(z: np.ndarray, labels: np.ndarray, kinds: np.ndarray) -> tuple[list[float], list[float]]:
    """Platt scaling fitted for each action type alone: (scales, biases) in TYPES order; a type
    absent from the data keeps the one fitted to all."""
    every = fit_platt(z, labels)
    fits = [
        fit_platt(z[kinds == k], labels[kinds == k]) if np.any(kinds == k) else every
        for k in range(len(TYPES))
    ]
    return [round(a, 4) for a, _ in fits], [round(b, 4) for _, b in fits]


def per_type_logits(z: np.ndarray, kinds: np.ndarray, scales: list[float], biases: list[float]) -> np.ndarray:
    """The logits read through each execution's own type's scaling (as sigmoid(1 * z' + 0))."""
    return np.array(scales)[kinds] * z + np.array(biases)[kinds]


def fit_platt(z: np.ndarray, labels: np.ndarray) -> tuple[float, float]:
    """(a, b) of sigmoid(a z + b) fitted to the labels by maximum likelihood (Newton's method
    on the two parameters, a little ridge so that separable data stays finite)."""
    y = labels.astype(float)
    x = np.stack([z, np.ones_like(z)], 1)
    w = np.array([1.0, 0.0])
    for _ in range(NEWTON_STEPS):
        p = 1 / (1 + np.exp(-(x @ w)))
        gradient = x.T @ (p - y) + 1e-3 * w
        hessian = (x * (p * (1 - p))[:, None]).T @ x + 1e-3 * np.eye(2)
        step = np.linalg.solve(hessian, gradient)
        w = w - step
        if np.abs(step).max() < 1e-8:
            break
    return float(w[0]), float(w[1])


def _nll(p: np.ndarray, y: np.ndarray) -> float:
    p = np.clip(p, 1e-6, 1 - 1e-6)
    return float(-(y * np.log(p) + (1 - y) * np.log(1 - p)).mean())


def report(z: np.ndarray, labels: np.ndarray, scale: float, bias: float) -> HeadReport:
    y = labels.astype(float)
    raw, calibrated = 1 / (1 + np.exp(-z)), 1 / (1 + np.exp(-(scale * z + bias)))
    return HeadReport(
        executions=len(y),
        rate=round(float(y.mean()), 4),
        mean_raw=round(float(raw.mean()), 4),
        mean_calibrated=round(float(calibrated.mean()), 4),
        nll_raw=round(_nll(raw, y), 4),
        nll_calibrated=round(_nll(calibrated, y), 4),
        auc=round(roc_auc(raw, labels), 4),
    )


def calibrate(net: PredictionNet, data: Dataset, limit: int | None = None) -> dict:
    """Platt scaling fitted on val, one for all action types and one per type, and the head on
    val and test with each: a JSON-ready record."""
    z, y, kinds = head_logits(net, data, "val", limit)
    scale, bias = fit_platt(z, y)
    scales, biases = fit_per_type(z, y, kinds)
    out = {"choice_scale": round(scale, 4), "choice_bias": round(bias, 4), "fitted_on": "val"}
    out |= {"choice_scales": scales, "choice_biases": biases}
    out["val"] = asdict(report(z, y, scale, bias))
    out["val_per_type"] = asdict(report(per_type_logits(z, kinds, scales, biases), y, 1.0, 0.0))
    z, y, kinds = head_logits(net, data, "test", limit)
    out["test"] = asdict(report(z, y, scale, bias))
    out["test_per_type"] = asdict(report(per_type_logits(z, kinds, scales, biases), y, 1.0, 0.0))
    return out


def read_calibration(run: str | Path) -> dict | None:
    """The calibration `afford eval prediction` wrote in a run, or None."""
    path = Path(run) / CALIBRATION_FILE
    if not path.is_file():
        return None
    record = json.loads(path.read_text())
    config = {k: record[k] for k in ("choice_scale", "choice_bias") if k in record}
    if "choice_scales" in record:  # fitted per action type (absent in runs calibrated before)
        config |= {k: tuple(record[k]) for k in ("choice_scales", "choice_biases")}
    return config or None


def format_calibration(record: dict) -> str:
    """The choice head's calibration a run's calibration.json holds, a line or three."""
    return "\n".join(_head_lines(record) if "choice_scale" in record else [])


def _head_lines(record: dict) -> list[str]:
    scale, bias = record["choice_scale"], record["choice_bias"]
    lines = [f"choice head, side effect follows: sigmoid({scale} z + {bias}) (Platt scaling, fitted on val)"]
    for split in ("val", "test"):
        r = record[split]
        lines.append(
            f"  {split}: {r['executions']} executions, {r['rate']:.3f} with a side effect; mean "
            f"probability {r['mean_raw']:.3f} raw, {r['mean_calibrated']:.3f} calibrated; log-loss "
            f"{r['nll_raw']:.4f} -> {r['nll_calibrated']:.4f}; ROC AUC {r['auc']:.3f}"
        )
    if "choice_scales" in record:
        fits = ", ".join(
            f"{kind} sigmoid({a} z + {b})"
            for kind, a, b in zip(TYPES, record["choice_scales"], record["choice_biases"], strict=True)
        )
        lines.append(f"  per action type (what the config keeps): {fits}")
        for split in ("val", "test"):
            r = record[f"{split}_per_type"]
            lines.append(
                f"  {split}: mean probability {r['mean_calibrated']:.3f}, log-loss {r['nll_calibrated']:.4f}"
            )
    return lines
