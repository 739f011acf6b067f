"""Why the learned planner fails random tasks: each failure of a random-task run diagnosed.

    afford bench random --n 100 --seed 0 --max-steps 2 --planner learned --out R2.json
    python benchmarks/random_failures.py R2.json --max-steps 2 [--weights DIR] [--json]

`afford bench random` says how many random tasks the learned planner solves; this says why it
fails the rest. Each task it failed is made again from its seed (the same random scene and
executions, so --max-steps and --min-steps must be the run's) and handed to `afford
diagnose`'s replay (planning/diagnose.py): the oracle's plan run through the learned nets names
the cause (oracle fails, execution, recognition, goal, prediction). A recognition failure is
split by where the oracle's action went unrecognised: on the real start image (Table 1's
recall) or on a state the net predicted (the prediction drawn too poorly to recognise on).
"""

from __future__ import annotations

import argparse
import json
from collections import Counter
from pathlib import Path


def where(d) -> str:
    """The cause, with a recognition failure placed on the real image or a predicted one."""
    if d.cause != "recognition":
        return d.cause
    missed = next(i for i, s in enumerate(d.steps) if not s.recognised)
    kind = d.steps[missed].action
    return f"recognition, {'start image' if missed == 0 else 'predicted state'} ({kind})"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("bench", metavar="FILE.json", help="`afford bench random --out`'s file")
    ap.add_argument("--max-steps", type=int, required=True, help="the run's --max-steps")
    ap.add_argument("--min-steps", type=int, default=1, help="the run's --min-steps")
    ap.add_argument("--planner", default="learned", help="the planner whose failures to diagnose")
    ap.add_argument("--weights", metavar="DIR", help="the run's weights folder (default: the shipped one)")
    ap.add_argument("--json", action="store_true")
    args = ap.parse_args()
    try:
        rows = json.loads(Path(args.bench).read_text())["tasks"]
    except (OSError, ValueError, KeyError) as e:
        raise SystemExit(f"random_failures: {args.bench}: not a random-task run's output ({e})") from None
    failed = [r for r in rows if args.planner in r and not r[args.planner]["solved"]]

    import torch
    from tqdm import tqdm

    from afford.planning.diagnose import diagnose
    from afford.planning.random_tasks import random_task
    from afford.shipped import Nets
    from afford.sim.scene import Scene

    torch.set_num_threads(2)
    learned = Nets(args.weights)
    scene = Scene()
    found = []
    for r in tqdm(failed, desc="diagnose", unit="task", disable=args.json):
        task = random_task(scene, r["seed"], max_steps=args.max_steps, min_steps=args.min_steps)
        if task is None or task.name != r["task"] or task.max_steps != r["steps"]:
            mismatch = f"seed {r['seed']} makes another task: are --max-steps and --min-steps the run's?"
            raise SystemExit(f"random_failures: {mismatch}")
        d = diagnose(task, scene, learned)
        found.append({"task": task.name, "steps": r["steps"], "cause": where(d), "diagnosis": d.to_dict()})
        if not args.json:
            tqdm.write(d.describe())
    scene.close()
    causes = Counter(f["cause"] for f in found)
    if args.json:
        out = {"tasks": len(rows), "failed": len(failed), "causes": causes, "failures": found}
        print(json.dumps(out, indent=2))
        return
    print(f"\n{args.planner}: {len(failed)} of {len(rows)} random tasks failed")
    for cause, n in causes.most_common():
        names = ", ".join(f["task"].removeprefix("random-") for f in found if f["cause"] == cause)
        print(f"  {n:3d}  {cause}  (seeds {names})")


if __name__ == "__main__":
    from afford.errors import exit_on_user_error

    exit_on_user_error(main)
