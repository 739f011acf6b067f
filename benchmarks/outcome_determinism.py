"""Is a side effect decided by the state the camera sees, or by chance? (Issue: side effects.)

    python benchmarks/outcome_determinism.py --data data/fresh [--split test --limit 400 --runs 8] [--json]

The prediction net draws one image per outcome. If an action's side effect, or where a pushed or
fallen object lands, changed from one execution to the next in a state that looks the same,
no net could draw it, and foresight would have a ceiling below 1 set by physics. This script
measures that. It replays a dataset's sequences in the simulator (sequence i is made again from
its seed, then its recorded actions are executed in order), and before every recorded step it
executes the same action again `--runs` times from the same state, its target moved each time
by a Gaussian offset of `--jitter` metres (clipped at two standard deviations; a pixel is about
5 mm on the table), so that each run starts from a state the camera cannot tell apart. Each run
is labelled by data/effects.py. Reported, per action type:

- canonical steps: the share of their runs that had a side effect;
- side-effect steps: the share of runs with the same kinds of effect, with any side effect,
  and how far (in pixels of the 128-pixel image) each affected object ended from where it
  ended in the recorded execution (an object on the table in one and gone in the other counts
  as infinitely far).

A step is measured only where the replay has not drifted from the record (every object within
2 mm of its recorded pose), so the measure is of the recorded state.

What the camera does not see (a support hidden under the block) is a separate question,
answered by benchmarks/place_outcomes.py.
"""

from __future__ import annotations

import argparse
import json
from dataclasses import dataclass, field, replace

import numpy as np

DRIFT = 0.002  # metres: a replayed state this far from the recorded one is not measured
FAR_PX = 3.0  # pixels: a landing further than this from the recorded one counts as apart


@dataclass
class StepRuns:
    """One recorded step executed again `runs` times from its state."""

    type: str
    kinds: tuple[str, ...]  # the recorded execution's side effects
    same: list[bool] = field(default_factory=list)  # each run's kinds equal the recorded ones
    side: list[bool] = field(default_factory=list)  # each run had some side effect
    landing_px: list[float] = field(default_factory=list)  # per run and affected object


def jittered(affordance, rng: np.random.Generator, jitter: float):
    offset = np.clip(rng.normal(0.0, jitter, 2), -2 * jitter, 2 * jitter)
    x, y, z = affordance.position
    return replace(affordance, position=(x + offset[0], y + offset[1], z))


def landing_distances(effects, recorded: np.ndarray, after: np.ndarray) -> list[float]:
    from afford.sim.camera import world_to_pixel

    out = []
    for e in effects:
        a, b = recorded[e.slot, :3], after[e.slot, :3]
        if np.isnan(a[0]) and np.isnan(b[0]):
            continue
        if np.isnan(a[0]) or np.isnan(b[0]):
            out.append(float("inf"))
        else:
            out.append(float(np.linalg.norm(world_to_pixel(a) - world_to_pixel(b))))
    return out


def measure(data, split: str, limit: int, runs: int, jitter: float, seed: int = 0) -> list[StepRuns]:
    from tqdm import tqdm

    from afford.data import effects as fx
    from afford.data.draws import pose_array
    from afford.sim.affordance import decode_affordance
    from afford.sim.layout import LayoutConfig, random_layout
    from afford.sim.scene import Scene

    rng = np.random.default_rng(seed)
    found: list[StepRuns] = []
    with Scene() as scene:
        for i in tqdm(list(data.indices(split))[:limit], desc="replay", unit="seq"):
            seq = data.sequence(i)
            layout = random_layout(np.random.default_rng([data.manifest.seed, seq.index]), LayoutConfig())
            scene.reset(layout, check=False)  # as `data/shard.make_sequence` made it
            for t, step in enumerate(fx.sequence_effects(seq)):
                before = pose_array(scene)
                action = decode_affordance(seq.actions[t])
                start = scene.snapshot()
                if np.nanmax(np.abs(before[:, :3] - seq.poses[t][:, :3])) < DRIFT:
                    held = seq.slots.index(scene.held) if scene.held else -1
                    record = StepRuns(step.type, tuple(sorted(step.kinds)))
                    for _ in range(runs):
                        scene.restore(start)
                        scene.execute(jittered(action, rng, jitter))
                        after = pose_array(scene)
                        now_held = seq.slots.index(scene.held) if scene.held else -1
                        label = fx.step_effects(before, after, held, now_held, seq.actions[t], seq.slots)
                        record.same.append(tuple(sorted(label.kinds)) == record.kinds)
                        record.side.append(bool(label.effects))
                        record.landing_px += landing_distances(step.effects, seq.poses[t + 1], after)
                    found.append(record)
                scene.restore(start)
                scene.execute(action)  # as recorded, to carry on to the next step
    return found


def summarise(steps: list[StepRuns]) -> dict:
    from afford.sim.affordances import TYPES

    canonical = [s for s in steps if not s.kinds]
    out = {
        "steps": len(steps),
        "canonical": {
            "steps": len(canonical),
            "runs_with_side_effect": round(float(np.mean([np.mean(s.side) for s in canonical])), 4)
            if canonical
            else None,
        },
        "side": {},
    }
    for group in ("all", *TYPES):
        chosen = [s for s in steps if s.kinds and group in ("all", s.type)]
        if not chosen:
            continue
        landing = np.array([d for s in chosen for d in s.landing_px])
        finite = landing[np.isfinite(landing)]
        out["side"][group] = {
            "steps": len(chosen),
            "same_kinds": round(float(np.mean([np.mean(s.same) for s in chosen])), 4),
            "any_side_effect": round(float(np.mean([np.mean(s.side) for s in chosen])), 4),
            "landing_px_median": round(float(np.median(finite)), 2) if len(finite) else None,
            "landing_apart": round(float(np.mean(landing > FAR_PX)), 4) if len(landing) else None,
            "landings": int(len(landing)),
        }
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--data", required=True, metavar="DIR", help="a dataset made by `afford generate`")
    ap.add_argument("--split", default="test", choices=("train", "val", "test"))
    ap.add_argument("--limit", type=int, default=400, metavar="N", help="the split's first N sequences")
    ap.add_argument("--runs", type=int, default=8, metavar="K", help="executions again per recorded step")
    ap.add_argument("--jitter", type=float, default=0.0015, metavar="M", help="target offset sd, metres")
    ap.add_argument("--json", action="store_true")
    args = ap.parse_args()

    from afford.data.format import Dataset

    data = Dataset(args.data)
    summary = summarise(measure(data, args.split, args.limit, args.runs, args.jitter))
    settings = {"split": args.split, "limit": args.limit, "runs": args.runs, "jitter_m": args.jitter}
    summary["settings"] = settings
    if args.json:
        print(json.dumps(summary, indent=1))
        return
    c = summary["canonical"]
    print(f"{summary['steps']} steps measured")
    print(f"canonical steps {c['steps']}: share of runs with a side effect {c['runs_with_side_effect']}")
    head = ("steps", "same kinds", "any effect", "landing px", f"> {FAR_PX:g} px")
    print(f"{'side-effect steps':18s} " + " ".join(f"{h:>11s}" for h in head))
    for group, s in summary["side"].items():
        far = s["landing_apart"]
        print(
            f"{group:18s} {s['steps']:11d} {s['same_kinds']:11.2f} {s['any_side_effect']:11.2f} "
            f"{s['landing_px_median']!s:>11s} {far!s:>11s}"
        )


if __name__ == "__main__":
    from afford.errors import exit_on_user_error

    exit_on_user_error(main)
