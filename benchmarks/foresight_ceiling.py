"""What share of side-effect foresight is where an object lands? (Issue: side effects.)

    python benchmarks/foresight_ceiling.py --data data/fresh [--split test] [--json]

Foresight (prediction/foresight.py) compares the prediction's error with the copy's over disks
around each affected object before and after the step. The copy's error there has two parts:
where objects were and are no longer (the leaving), and where they end up (the landing: the
after positions' disks outside every before disk). A net that drew every leaving perfectly
and never the landing would score 1 - (the landing's share of the copy's error). This script
reads that share from a dataset's true images, no net involved, per action type and kind of
effect: the foresight of a perfect "it leaves, I cannot say where to" predictor.
"""

from __future__ import annotations

import argparse
import json

import numpy as np


def landing_shares(data, split: str, limit: int | None) -> dict[str, tuple[float, float]]:
    """Per group: (the copy's error over the side-effect disks, the part on the landing disks)."""
    from afford.data import effects as fx
    from afford.prediction.foresight import execution_batches, pixel_errors
    from afford.sim.affordance import Col

    sums: dict[str, list[float]] = {}
    for batch in execution_batches(data, split, limit):
        for step, seq, t in batch:
            if not step.effects:
                continue
            before, after, action = seq.poses[t], seq.poses[t + 1], seq.actions[t]
            place = np.asarray(action[Col.POSITION], dtype=float)
            mask = fx.step_mask(step, before, after, action)
            landing = fx.landing_mask(list(step.effects), before, after, place)  # inside mask
            copy = pixel_errors(seq.image(t), seq.image(t + 1))
            for key in ("all", step.type, *step.kinds):
                total = sums.setdefault(key, [0.0, 0.0, 0])
                total[0] += float(copy[mask].sum())
                total[1] += float(copy[landing].sum())
                total[2] += 1
    return sums


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--data", required=True, metavar="DIR", help="a dataset made by `afford generate`")
    ap.add_argument("--split", default="test", choices=("train", "val", "test"))
    ap.add_argument("--limit", type=int, metavar="N", help="the split's first N sequences only")
    ap.add_argument("--json", action="store_true")
    args = ap.parse_args()

    from afford.data.format import Dataset

    data = Dataset(args.data)
    sums = landing_shares(data, args.split, args.limit)
    summary = {
        key: {"ceiling": round(1 - land / total, 4), "executions": n}
        for key, (total, land, n) in sums.items()
        if total > 0
    }
    if args.json:
        print(json.dumps(summary, indent=1))
        return
    print(f"{'side effects':16s} {'executions':>10s} {'leaving-only foresight':>23s}")
    for key, s in summary.items():
        print(f"{key:16s} {s['executions']:10d} {s['ceiling']:23.2f}")


if __name__ == "__main__":
    from afford.errors import exit_on_user_error

    exit_on_user_error(main)
