"""How well the object dynamics predict where objects go, against copying the start state.

Every object of every execution falls in one group: the object acted on (per affordance type,
when it took no side effect), each side-effect kind it took (`data/effects.py`; an object can
take two, pushed and toppled), or still (on the table, neither acted on nor affected). An
object's error is the distance in the state image between its predicted and its true centre
(`sim/camera.world_to_pixel`; 1 px is about 5 mm on the table), infinite where it is on the
table but predicted gone. Objects that truly left the table are scored by the off-the-table F1.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from afford.data.effects import KINDS as EFFECT_KINDS
from afford.objects.dynamics import ObjectDynamics, ObjectOutcomes
from afford.objects.transitions import Transitions
from afford.sim.affordances import TYPES
from afford.sim.camera import world_to_pixel

NEAR_PX = 3.0
STILL_PX = 0.5
MISSING_PX = 1000.0  # the error of an object predicted gone that is still there: past any cut-off
SIDE = "all side-effect objects"
STILL = "still"
CHUNK = 4096  # executions predicted at once


def acted_group(kind: str) -> str:
    return f"acted on ({kind})"


GROUPS = (*[acted_group(t) for t in TYPES], *EFFECT_KINDS, SIDE, STILL)


@dataclass
class Errors:
    """Per group, the pixel errors of the model's likeliest outcome, of its best outcome, and
    of copying the start."""

    model: dict[str, list[float]] = field(default_factory=lambda: {g: [] for g in GROUPS})
    best: dict[str, list[float]] = field(default_factory=lambda: {g: [] for g in GROUPS})
    copy: dict[str, list[float]] = field(default_factory=lambda: {g: [] for g in GROUPS})


def pixel_error(pred: np.ndarray, true: np.ndarray) -> np.ndarray:
    """(...,) image distance between predicted and true centres; MISSING_PX where predicted gone."""
    gone = np.isnan(pred[..., 0])
    d = np.linalg.norm(world_to_pixel(np.nan_to_num(pred[..., :3])) - world_to_pixel(true[..., :3]), axis=-1)
    return np.where(gone, MISSING_PX, d)


# A world model's dynamics: (start poses, held slots, affordance rows) -> ObjectOutcomes.
Predictor = Callable[[np.ndarray, np.ndarray, np.ndarray], ObjectOutcomes]


def simulator_predictor() -> Predictor:
    """The simulator itself, run from the given start states (`simulated.py`)."""
    from afford.objects.simulated import simulate
    from afford.sim.scene import Scene

    scene = Scene()
    return lambda before, held, actions: simulate(scene, before, held, actions)


def predict_all(predictor: Predictor, t: Transitions, before: np.ndarray | None = None) -> ObjectOutcomes:
    """Outcomes of every execution, from the true start states or from `before` (perceived)."""
    start = t.before if before is None else before
    parts = [
        predictor(
            start[i : i + CHUNK],
            t.held_before[i : i + CHUNK],
            t.actions[i : i + CHUNK],
        )
        for i in range(0, len(t), CHUNK)
    ]
    return ObjectOutcomes(
        *(np.concatenate([getattr(p, f) for p in parts]) for f in ("poses", "held", "probability"))
    )


def measure(predictor: Predictor | ObjectDynamics, t: Transitions, before: np.ndarray | None = None) -> dict:
    """The dynamics report on the executions `t` (see the module's docstring)."""
    if isinstance(predictor, ObjectDynamics):
        predictor = predictor.outcomes
    outcomes = predict_all(predictor, t, before)
    likely, _ = outcomes.likeliest()
    effects = t.effects()
    errors = Errors()
    gone_true, gone_pred = [], []
    correct, prob = [], []
    for i, step in enumerate(effects):
        by_slot: dict[int, list[str]] = {}
        for e in step.effects:
            by_slot.setdefault(e.slot, []).append(e.kind)
        for slot in range(t.before.shape[1]):
            if np.isnan(t.before[i, slot, 0]):
                continue
            truly_gone = np.isnan(t.after[i, slot, 0])
            gone_true.append(truly_gone)
            gone_pred.append(bool(np.isnan(likely[i, slot, 0])))
            if truly_gone:
                continue
            groups = by_slot.get(slot, [])
            if groups:
                groups = [*groups, SIDE]
            elif slot == step.acted:
                groups = [acted_group(step.type)]
            else:
                groups = [STILL]
            model = float(pixel_error(likely[i, slot], t.after[i, slot]))
            best = float(pixel_error(outcomes.poses[i, :, slot], t.after[i, slot]).min())
            copy = float(pixel_error(t.before[i, slot], t.after[i, slot]))
            for g in groups:
                errors.model[g].append(model)
                errors.best[g].append(best)
                errors.copy[g].append(copy)
        # Calibration: how often each outcome is the one nearest to what happened.
        # Where every outcome is the same prediction, which one the head picks does not matter.
        credit = nearest_share(t.after[i], outcomes.poses[i], ~np.isnan(t.before[i, :, 0]))
        if credit.min() < credit.max():
            correct += list(credit)
            prob += list(outcomes.probability[i])
    return {
        "executions": len(t),
        "groups": {g: _summary(errors, g) for g in GROUPS if errors.model[g]},
        "off_table_f1": _f1(np.array(gone_true), np.array(gone_pred)),
        "calibration": _calibration(np.array(prob), np.array(correct)),
    }


def nearest_share(after: np.ndarray, poses: np.ndarray, was: np.ndarray, tie_px: float = 0.5) -> np.ndarray:
    """(K,) each outcome's share in being the one nearest the truth: its error summed over the
    objects on the table before (each capped at NEAR_PX * 10; an object gone in one and not the
    other costs the cap), one for the nearest, shared evenly among outcomes within `tie_px`."""
    cap = NEAR_PX * 10
    gone = np.isnan(after[:, 0])
    cost = []
    for pred in poses:
        pred_gone = np.isnan(pred[:, 0])
        err = np.where(gone | pred_gone, np.where(gone == pred_gone, 0.0, cap), 0.0)
        both = ~gone & ~pred_gone & was
        err[both] = np.minimum(pixel_error(pred[both], after[both]), cap)
        cost.append(float(err[was].sum()))
    cost = np.array(cost)
    best = cost <= cost.min() + tie_px
    return best / best.sum()


def _summary(errors: Errors, g: str) -> dict:
    m, b, c = (np.array(x[g]) for x in (errors.model, errors.best, errors.copy))
    return {
        "n": len(m),
        "copy_median_px": float(np.median(c)),
        "copy_p90_px": float(np.percentile(c, 90)),
        "median_px": float(np.median(m)),
        "p90_px": float(np.percentile(m, 90)),
        "within_3px": float(np.mean(m < NEAR_PX)),
        "within_0.5px": float(np.mean(m < STILL_PX)),
        "best_of_k_within_3px": float(np.mean(b < NEAR_PX)),
        "best_of_k_median_px": float(np.median(b)),
    }


def _f1(truth: np.ndarray, pred: np.ndarray) -> dict:
    tp = int(np.sum(truth & pred))
    fp = int(np.sum(~truth & pred))
    fn = int(np.sum(truth & ~pred))
    precision = tp / (tp + fp) if tp + fp else 0.0
    recall = tp / (tp + fn) if tp + fn else 0.0
    f1 = 2 * precision * recall / (precision + recall) if precision + recall else 0.0
    return {"f1": f1, "precision": precision, "recall": recall, "gone": int(truth.sum())}


def _calibration(prob: np.ndarray, correct: np.ndarray, bins: int = 10, least: int = 20) -> dict:
    """Per decile of predicted probability, the share of outcomes that were the nearest to what
    happened (`nearest_share`); the largest gap over deciles holding at least `least` outcomes."""
    edges = np.linspace(0, 1, bins + 1)
    rows = []
    for lo, hi in zip(edges[:-1], edges[1:], strict=True):
        inside = (prob >= lo) & ((prob < hi) | (hi == 1.0))
        if inside.sum():
            rows.append(
                {
                    "from": lo,
                    "to": hi,
                    "n": int(inside.sum()),
                    "mean_p": float(prob[inside].mean()),
                    "share_nearest": float(correct[inside].mean()),
                }
            )
    gaps = [abs(r["mean_p"] - r["share_nearest"]) for r in rows if r["n"] >= least]
    return {"deciles": rows, "largest_gap": max(gaps) if gaps else None, "outcomes": len(prob)}


def table(report: dict) -> str:
    """The report as a text table, one row a group."""
    head = (
        f"{'objects':26s} {'n':>6s} {'copy med/p90':>13s} {'model med/p90':>14s} "
        f"{'<3px':>6s} {'<0.5px':>7s} {'best<3px':>9s}"
    )
    lines = [head, "-" * len(head)]
    for g, r in report["groups"].items():
        lines.append(
            f"{g:26s} {r['n']:6d} {r['copy_median_px']:6.1f}/{r['copy_p90_px']:<6.1f} "
            f"{r['median_px']:6.2f}/{r['p90_px']:<7.2f} {r['within_3px']:6.2f} {r['within_0.5px']:7.2f} "
            f"{r['best_of_k_within_3px']:9.2f}"
        )
    f1 = report["off_table_f1"]
    lines.append(
        f"off the table: F1 {f1['f1']:.3f} (precision {f1['precision']:.3f}, "
        f"recall {f1['recall']:.3f}, n {f1['gone']})"
    )
    cal = report["calibration"]
    gap = cal["largest_gap"]
    lines.append("calibration, largest gap over deciles: " + ("n/a" if gap is None else f"{gap:.3f}"))
    return "\n".join(lines)
