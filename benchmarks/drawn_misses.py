"""Which affordances the recognition net misses on the object world model's drawn states.

    python benchmarks/drawn_misses.py [--data data/part] [--split test] [--objects DIR] [--json]

Each run of the split is started from its first image (perceived), moved one step by the
dynamics (the likeliest outcome, rested) and drawn by the rollout that `afford eval prediction
--objects` measures (`objects/rollout.py`); the recognition net runs on the drawn state and on
the true one. Every affordance of the true next state that is found on the true image and not
on the drawn one is put down to the object it belongs to (the true object nearest it over the
table), by the action of the step, whether that object moved in the step and its kind, with how
far the dynamics put it from where it went (the nearest predicted object of its kind). It says
which stage loses the affordances that recognition on drawn states misses: where the objects
were drawn, or how.
"""

from __future__ import annotations

import argparse
import json
from collections import defaultdict

import numpy as np
import torch

from afford.data.format import Dataset
from afford.data.torch_data import PredictionData, collate_prediction
from afford.metrics import matches
from afford.objects.rollout import ObjectRollout
from afford.objects.state import KINDS, SLOT_KIND
from afford.shipped import Nets
from afford.sim.affordance import decode_affordance

STILL_M = 0.002  # an object that moved less than this in the step stayed


def misses(data: Dataset, split: str, objects: str | None) -> dict:
    nets = Nets(objects)
    world = ObjectRollout(nets.perception, nets.dynamics)
    recognise = nets.recognizer
    runs = PredictionData(data, split, max_steps=1, random_start=False)
    groups: dict[str, list[float]] = defaultdict(list)
    found = {"drawn": 0, "true": 0, "total": 0}
    for k in range(len(runs)):
        images, actions, _ = collate_prediction([runs[k]])
        seq = data.sequence(runs.indices[k])
        drawn, after = world.roll(images[:, 0], actions)
        after = after[0, 0]
        on_drawn, on_true = recognise(torch.cat([drawn[:, 0], images[:, 1]]))
        action = decode_affordance(actions[0, 0].numpy()).type
        before, went = seq.poses[0], seq.poses[1]
        present = [s for s in range(len(went)) if not np.isnan(went[s, 0])]
        for a in (decode_affordance(r) for r in seq.affordances[1]):
            hit_drawn = any(matches(d.affordance, a) for d in on_drawn)
            hit_true = any(matches(d.affordance, a) for d in on_true)
            found["total"] += 1
            found["drawn"] += hit_drawn
            found["true"] += hit_true
            if hit_drawn or not hit_true or not present:
                continue
            s = min(present, key=lambda q: np.linalg.norm(went[q, :2] - np.asarray(a.position[:2])))
            still = not np.isnan(before[s, 0]) and np.linalg.norm(went[s, :3] - before[s, :3]) < STILL_M
            same = [q for q in np.flatnonzero(SLOT_KIND == SLOT_KIND[s]) if not np.isnan(after[q, 0])]
            off = min((float(np.linalg.norm(after[q, :3] - went[s, :3])) for q in same), default=float("inf"))
            name = f"{a.type} after a {action}, {KINDS[SLOT_KIND[s]]} {'stayed' if still else 'moved'}"
            groups[name].append(off)
    return {
        "runs": len(runs),
        "recall_drawn": found["drawn"] / max(found["total"], 1),
        "recall_true": found["true"] / max(found["total"], 1),
        "missed_on_drawn_only": {
            name: {"n": len(v), "placed_off_mm_median": 1000 * float(np.median(v))}
            for name, v in sorted(groups.items(), key=lambda kv: -len(kv[1]))
        },
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--data", default="data/part")
    parser.add_argument("--split", default="test")
    parser.add_argument(
        "--objects", metavar="DIR", help="a weights folder whose nets to measure (else the shipped)"
    )
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args()
    r = misses(Dataset(args.data), args.split, args.objects)
    if args.json:
        print(json.dumps(r, indent=2))
        return
    print(f"{r['runs']} runs, one step: recall {r['recall_drawn']:.3f} drawn, {r['recall_true']:.3f} true")
    print(f"{'found on the true state, missed on the drawn one':52s} {'n':>4s} {'placed off (mm)':>16s}")
    for name, g in r["missed_on_drawn_only"].items():
        print(f"{name:52s} {g['n']:4d} {g['placed_off_mm_median']:16.1f}")


if __name__ == "__main__":
    main()
