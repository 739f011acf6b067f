"""Uncertain outcomes through the two-outcome net's own branches (paper V), measured.

    python benchmarks/branch_risk.py [--weights DIR] [--tasks tasks/uncertain] [--risks 0,1,3]
        [--perturb 0.005,3] [--executions 20] [--json]

A prediction net with two outcomes per step and a head that weighs them is a mixture: each
state of the branching tree (planning/branches.py) holds outcomes with probabilities p and
eq. (5) losses L, so beside the expected loss sum p L it has a standard deviation
sqrt(sum p (L - sum p L)^2). This plans each task with the score expected loss + risk x that
standard deviation (sign flipped for a negative goal; what `afford plan --outcomes expected
--risk R` does), executes each plan from perturbed
starts, and prints the success rates; then, per task, the best end states of the plain
expected score with their branch probabilities and losses: whether the head tells a risky
place from a safe one decides whether any risk weight can.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np

SHOWN = 4  # end states listed per task


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--weights", metavar="DIR", help="a weights folder (default: the shipped one)")
    ap.add_argument("--tasks", default="tasks/uncertain", metavar="DIR")
    ap.add_argument("--risks", default="0,1,3", help="comma-separated risk weights")
    ap.add_argument("--perturb", default="0.005,3", metavar="METRES,DEGREES")
    ap.add_argument("--executions", type=int, default=20)
    ap.add_argument("--json", action="store_true")
    args = ap.parse_args()

    from afford.planning.branches import BranchingModel
    from afford.planning.run import perturbed_successes
    from afford.planning.strategies import search
    from afford.planning.tasks import load_task
    from afford.planning.tree import SearchConfig
    from afford.shipped import Nets
    from afford.sim.perturb import Perturbation
    from afford.sim.scene import Scene

    risks = [float(r) for r in args.risks.split(",")]
    perturbation = Perturbation(*[float(v) for v in args.perturb.split(",")])
    nets = Nets(args.weights)
    quiet = SearchConfig(progress=False)
    scene = Scene()
    rows = []
    for f in sorted(Path(args.tasks).glob("*.json")):
        task = load_task(f, scene)
        row = {"task": task.name, "risks": {}, "ends": []}
        for risk in risks:
            scene.reset(task.scene)
            model = BranchingModel(scene.observe(), nets.recognizer, nets.predictor, risk)
            tree = search(model, task.goal, task.max_steps, quiet)
            wins = perturbed_successes(tree.plan, task, scene, perturbation, args.executions)
            row["risks"][risk] = {
                "perturbed_success_rate": float(np.mean(wins)),
                "plan": [a.type + str(tuple(round(v, 3) for v in a.position[:2])) for a in tree.plan],
            }
            if risk == 0.0:
                moved = [n for n in tree.nodes if n.plan and n.plan[-1].type != "grasp"]
                ends = sorted(moved, key=lambda n: n.loss)
                for n in ends[:SHOWN]:
                    a = n.plan[-1]
                    row["ends"].append(
                        {
                            "action": a.type + str(tuple(round(v, 3) for v in a.position[:2])),
                            "probability": np.round(n.state.probability, 2).tolist(),
                            "loss": np.round(task.goal.loss(n.state.images), 4).tolist(),
                        }
                    )
        rows.append(row)
        if not args.json:
            cells = "   ".join(
                f"risk {r:g}: {v['perturbed_success_rate']:.0%} {' '.join(v['plan']) or '(nothing)'}"
                for r, v in row["risks"].items()
            )
            print(f"{task.name:32s} {cells}")
            for e in row["ends"]:
                print(f"    {e['action']:24s} branches p {e['probability']}  eq. (5) {e['loss']}")
    if args.json:
        print(json.dumps(rows, indent=2))


if __name__ == "__main__":
    from afford.errors import exit_on_user_error

    exit_on_user_error(main)
