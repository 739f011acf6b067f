"""Is the ensemble's spread calibrated? A larger spread should mean a larger error (paper V).

    python benchmarks/ensemble_calibration.py --data data/cpu [--weights DIR] [--runs 300]
        [--out out/calibration] [--json]

Every member rolls out test runs from their first state through all their executions (as
Table 2 is measured). Per predicted state: the members' mean per-pixel spread, and the
absolute RGBD error of their mean image against the true state. Prints Spearman's rank
correlation of the two over the states (and over sampled pixels), the error in five
equal-count bins of spread, and the same per prediction step; writes OUT/calibration.png.

The predicted variance (the members' variance heads plus their spread, prediction/variance.py)
against the squared error: the spread-to-error ratio sqrt(mean variance / mean squared error)
on val, the scale factor that makes it 1 there, the ratio on test raw and scaled, Spearman
over test states, and a reliability curve (predicted against actual RMS error, pixels binned
by predicted variance) in the picture's third panel.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

DISAGREE = 1e-3  # a pixel's spread above which the members count as disagreeing there


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--data", required=True, metavar="DIR")
    ap.add_argument(
        "--weights", metavar="DIR", help="a weights folder with ensemble/ (default: the shipped one)"
    )
    ap.add_argument("--runs", type=int, default=300, help="test runs rolled out (default 300)")
    ap.add_argument("--out", default="out/calibration", metavar="DIR")
    ap.add_argument("--json", action="store_true")
    args = ap.parse_args()

    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import matplotlib.ticker
    import numpy as np
    import torch

    from afford.data.format import Dataset
    from afford.prediction.ensemble import calibrate, spearman
    from afford.shipped import Nets

    members = Nets(args.weights).members
    torch.set_num_threads(members[0].config.training.threads)
    data = Dataset(args.data)
    val = calibrate(members, data, "val", limit=args.runs)
    cal = calibrate(members, data, "test", limit=args.runs)
    scale = val.fitted_scale()
    what = "members' spread"
    live = cal.pixel_spread > DISAGREE
    report = {
        "members": len(members),
        "states": len(cal.spread),
        "rank_correlation": round(cal.rank_correlation(), 4),
        "pixel_rank_correlation": round(spearman(cal.pixel_spread, cal.pixel_error), 4),
        "live_pixel_rank_correlation": round(spearman(cal.pixel_spread[live], cal.pixel_error[live]), 4),
        "live_pixels": int(live.sum()),
        "pixels": len(cal.pixel_spread),
        "error_over_spread": round(float(cal.error.mean() / cal.spread.mean()), 2),
        "by_spread": cal.by_spread(5),
        "variance": {
            "val_ratio": round(val.ratio(), 3),
            "fitted_scale": round(scale, 4),
            "test_ratio": round(cal.ratio(), 3),
            "test_ratio_scaled": round(cal.ratio(scale), 3),
            "test_rank_correlation": round(cal.variance_rank_correlation(), 4),
            "reliability": cal.reliability(8),
        },
        "by_step": {
            str(s): {
                "states": int((cal.step == s).sum()),
                "spread": float(cal.spread[cal.step == s].mean()),
                "error": float(cal.error[cal.step == s].mean()),
                "rank_correlation": round(spearman(cal.spread[cal.step == s], cal.error[cal.step == s]), 4),
            }
            for s in sorted(set(cal.step.tolist()))
        },
    }
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    fig, (a, b, c) = plt.subplots(1, 3, figsize=(15, 4))
    for s in sorted(set(cal.step.tolist())):
        pick = cal.step == s
        a.scatter(cal.spread[pick], cal.error[pick], s=6, alpha=0.5, label=f"step {s}")
    bins = report["by_spread"]
    a.plot([x["spread"] for x in bins], [x["error"] for x in bins], "k-o", label="5 bins of spread")
    a.set(
        xlabel=f"{what} (mean over the image)",
        ylabel="error of their mean (mean abs RGBD)",
        title=f"per predicted state: Spearman {report['rank_correlation']:.2f}",
    )
    a.legend(fontsize=7)
    a.grid(alpha=0.3)
    # Most pixels are background that every member leaves alone: the bins are of the pixels
    # where the members disagree at all.
    order = np.flatnonzero(live)[np.argsort(cal.pixel_spread[live])]
    parts = np.array_split(order, 10)
    b.loglog([cal.pixel_spread[p].mean() for p in parts], [cal.pixel_error[p].mean() for p in parts], "k-o")
    b.set(
        xlabel=f"{what} at a pixel",
        ylabel="error of their mean there",
        title=f"pixels with spread > {DISAGREE:g}, 10 bins: "
        f"Spearman {report['live_pixel_rank_correlation']:.2f}",
    )
    b.grid(alpha=0.3, which="both")
    b.xaxis.set_minor_formatter(matplotlib.ticker.NullFormatter())  # a narrow range: labels overlap
    rel = report["variance"]["reliability"]
    predicted = np.array([x["predicted"] for x in rel])
    c.loglog(predicted, [x["actual"] for x in rel], "k-o", label="as the weights give it")
    c.loglog(
        predicted * np.sqrt(scale), [x["actual"] for x in rel], "C1-s", label=f"x {scale:.2g}, fitted on val"
    )
    ends = [
        min(predicted.min(), rel[0]["actual"]),
        max(predicted.max() * np.sqrt(max(scale, 1)), rel[-1]["actual"]),
    ]
    c.loglog(ends, ends, ":", color="grey", label="calibrated")
    c.set(
        xlabel="predicted RMS error at a pixel (sqrt of the variance)",
        ylabel="actual RMS error there",
        title=f"8 pixel bins: ratio {report['variance']['test_ratio_scaled']:.2f} scaled, "
        f"Spearman {report['variance']['test_rank_correlation']:.2f}",
    )
    c.legend(fontsize=7)
    c.grid(alpha=0.3, which="both")
    fig.tight_layout()
    fig.savefig(out / "calibration.png", dpi=110)
    if args.json:
        print(json.dumps(report, indent=2))
        return
    print(f"{report['members']} members, {report['states']} predicted test states")
    print(
        f"Spearman(spread, error): {report['rank_correlation']:.3f} over states, "
        f"{report['pixel_rank_correlation']:.3f} over pixels, {report['live_pixel_rank_correlation']:.3f} "
        f"over the {report['live_pixels']:,} of {report['pixels']:,} sampled pixels where they disagree "
        f"(spread > {DISAGREE:g})"
    )
    print(f"mean error / mean spread: {report['error_over_spread']:.1f}")
    v = report["variance"]
    print(
        f"variance: spread-to-error ratio {v['val_ratio']:.3f} on val -> scale {v['fitted_scale']:.4g}; "
        f"test {v['test_ratio']:.3f} raw, {v['test_ratio_scaled']:.3f} scaled; Spearman(variance, "
        f"squared error) over test states {v['test_rank_correlation']:.3f}"
    )
    for x in bins:
        print(f"  spread {x['spread']:.4f}: error {x['error']:.4f} ({x['states']} states)")
    for s, x in report["by_step"].items():
        print(
            f"  step {s}: spread {x['spread']:.4f} error {x['error']:.4f} "
            f"Spearman {x['rank_correlation']:.3f}"
        )
    print(f"picture: {out / 'calibration.png'}")


if __name__ == "__main__":
    from afford.errors import exit_on_user_error

    exit_on_user_error(main)
