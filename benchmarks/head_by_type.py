"""The choice head per action type: one Platt scaling for all types against one per type.

    python benchmarks/head_by_type.py --data data/part [--weights DIR] [--json]

A two-outcome prediction net's head says how likely a side effect is; `afford eval prediction`
calibrates it with one Platt scaling, sigmoid(a z + b), fitted on val over every execution
(prediction/calibration.py). Grasps, places and turns have side effects at very different
rates (3%, 16%, 46% on test), so one scaling may leave one type under- or overconfident. This
fits both on val and reports on test, per type: the share with a side effect, the mean
probability, the log-loss, and how many side effects the head picks (probability over 0.5:
the outcome the planner carries on) with what precision.
"""

from __future__ import annotations

import argparse
import json


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--data", required=True, metavar="DIR")
    ap.add_argument("--weights", metavar="DIR", help="a weights folder (default: the shipped one)")
    ap.add_argument("--json", action="store_true")
    args = ap.parse_args()

    import numpy as np
    import torch

    from afford.data.format import Dataset
    from afford.prediction.calibration import fit_per_type, fit_platt, head_logits
    from afford.shipped import Nets
    from afford.sim.affordances import TYPES

    net = Nets(args.weights).predictor.eval()
    if net.config.outcomes.hypotheses_by != "effect":
        raise SystemExit("head_by_type: the prediction net has no side-effect head")
    torch.set_num_threads(net.config.training.threads)
    data = Dataset(args.data)

    (zv, yv, tv), (zt, yt, tt) = head_logits(net, data, "val"), head_logits(net, data, "test")
    one = fit_platt(zv, yv)
    scales, biases = fit_per_type(zv, yv, tv)
    rows = []
    for k, kind in enumerate(TYPES):
        own = (scales[k], biases[k])
        z, y = zt[tt == k], yt[tt == k]
        for name, (a, b) in (("one for all", one), ("per type", own)):
            p = np.clip(1 / (1 + np.exp(-(a * z + b))), 1e-6, 1 - 1e-6)
            picked = p > 0.5
            rows.append(
                {
                    "type": kind,
                    "scaling": name,
                    "a": round(a, 3),
                    "b": round(b, 3),
                    "executions": int(len(y)),
                    "rate": round(float(y.mean()), 3),
                    "mean_probability": round(float(p.mean()), 3),
                    "nll": round(float(-(y * np.log(p) + (1 - y) * np.log(1 - p)).mean()), 3),
                    "picked": int(picked.sum()),
                    "recall": round(float((picked & y).sum() / max(y.sum(), 1)), 2),
                    "precision": round(float((picked & y).sum() / max(picked.sum(), 1)), 2),
                }
            )
    if args.json:
        print(json.dumps(rows, indent=1))
        return
    print("test split, fitted on val: type, scaling, a, b, executions, side-effect rate, mean probability,")
    print("log-loss, side effects picked (probability > 0.5), their share of the side effects, precision")
    numbers = ("a", "b", "executions", "rate", "mean_probability", "nll", "picked", "recall", "precision")
    for r in rows:
        print(f"{r['type']:6s} {r['scaling']:12s} " + " ".join(f"{r[k]:>6}" for k in numbers))


if __name__ == "__main__":
    from afford.errors import exit_on_user_error

    exit_on_user_error(main)
