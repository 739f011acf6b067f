"""Continuous turn angles (paper V): the best of +-90 against angles optimised through the net.

    python benchmarks/continuous_turns.py --weights runs/wcont [--tasks tasks/continuous]
        [--out out/continuous] [--json]

For every task of the folder (goals that a quarter turn cannot reach), plans with the learned
planner twice: as the paper does (the search tries +90 and -90 for every turn) and with
`--optimise-turns` (the best plan with turns, its angles then found by gradient descent on
eq. (5) through the prediction net). Each plan is executed in the simulator and judged.
Prints both outcomes, the angle found and the planning time, and writes OUT/curves.png, one
column per task: above, eq. (5) against the descent step, one line per restart; below, eq.
(5) of the best plan with a turn at every angle from -180 to 180, predicted by the net and
rendered after executing it in the simulator, the optimised angle marked. `--weights` should
hold a prediction net trained on continuous turns (`afford generate --turn-angles
continuous`, then `afford train prediction ... --init` the shipped run).
"""

from __future__ import annotations

import argparse
import json
from dataclasses import replace
from pathlib import Path


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--weights", required=True, metavar="DIR")
    ap.add_argument("--tasks", default="tasks/continuous", metavar="DIR")
    ap.add_argument("--out", default="out/continuous", metavar="DIR")
    ap.add_argument("--json", action="store_true")
    args = ap.parse_args()

    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from afford.planning.angles import optimise_turns
    from afford.planning.learned import LearnedModel
    from afford.planning.run import PlannerConfig, solve
    from afford.planning.strategies import search
    from afford.planning.tasks import load_task
    from afford.planning.tree import SearchConfig
    from afford.shipped import Nets
    from afford.sim.scene import Scene

    learned = Nets(args.weights)
    scene = Scene()
    files = sorted(Path(args.tasks).glob("*.json"))
    plain = PlannerConfig(search=SearchConfig(progress=False))
    rows, curves, sweeps = [], {}, {}
    for f in files:
        task = load_task(f, scene)
        quarter = solve(task, "learned", scene, plain, learned)
        tuned = solve(task, "learned", scene, replace(plain, optimise_turns=True), learned)
        turns = [round(a.turn, 1) for a in tuned.plan or () if a.turn]
        rows.append(
            {
                "task": task.name,
                "quarter_turns": {"solved": quarter.success, "seconds": round(quarter.seconds, 2)},
                "optimised": {"solved": tuned.success, "turns": turns, "seconds": round(tuned.seconds, 2)},
            }
        )
        # The descent's curves, for the picture: the best plan with a turn of the plain search.
        scene.reset(task.scene)
        model = LearnedModel(scene.observe(), learned.recognizer, learned.predictor)
        tree = search(model, task.goal, task.max_steps, plain.search)
        with_turn = [n for n in tree.nodes if any(a.turn for a in n.plan)]
        if with_turn:
            best = min(with_turn, key=lambda n: n.loss)
            found = optimise_turns(model.net, model.image, best.plan, task.goal)
            curves[task.name] = found.curves
            sweeps[task.name] = _sweep(model, scene, task, best.plan) + (
                [a.turn for a in found.plan if a.turn],
            )
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    cols = max(len(curves), 1)
    fig, axes = plt.subplots(2, cols, figsize=(4.5 * cols, 6.6), squeeze=False)
    for ax, (name, runs) in zip(axes[0], curves.items(), strict=False):
        for k, curve in enumerate(runs):
            ax.plot(curve, label=f"restart {k + 1}")
        ax.set(title=name, xlabel="gradient step", ylabel="eq. (5), predicted")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7)
    for ax, (angles, predicted, true, found) in zip(axes[1], sweeps.values(), strict=False):
        ax.plot(angles, predicted, label="predicted by the net")
        ax.plot(angles, true, label="executed in the simulator")
        for k, a in enumerate(found):
            ax.axvline(a, color="k", ls=":", label="optimised angle" if k == 0 else None)
        ax.set(xlabel="turn angle (every turn of the plan), degrees", ylabel="eq. (5)")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(out / "curves.png", dpi=110)
    if args.json:
        print(json.dumps(rows, indent=2))
        return
    for r in rows:
        q, o = r["quarter_turns"], r["optimised"]
        print(
            f"{r['task']:28s} +-90: {'solved' if q['solved'] else 'fails'} ({q['seconds']:.1f} s)   "
            f"optimised: {'solved' if o['solved'] else 'fails'} turns {o['turns']} ({o['seconds']:.1f} s)"
        )
    print(f"curves: {out / 'curves.png'}")


SWEEP = range(-180, 181, 10)  # the angles of the picture's lower row


def _sweep(model, scene, task, plan):
    """Eq. (5) of the plan's last state with every turn at each angle of SWEEP: predicted
    through the net, and rendered after executing it in the simulator."""
    import numpy as np
    import torch

    from afford.planning.judge import execute_plan
    from afford.sim.affordance import Col, encode_affordance

    turns = [i for i, a in enumerate(plan) if a.turn]
    image = torch.from_numpy(np.ascontiguousarray(model.image.transpose(2, 0, 1)))[None]
    rows = torch.from_numpy(np.stack([encode_affordance(a) for a in plan]))[None]
    predicted, true = [], []
    for angle in SWEEP:
        actions = rows.clone()
        actions[0, turns, Col.TURN] = float(angle) or 1e-3
        with torch.no_grad():
            predicted.append(float(task.goal.loss_torch(model.net.rollout(image, actions)[:, -1])[0]))
        turned = tuple(a.with_turn(float(angle) or 1e-3) if a.turn else a for a in plan)
        end = execute_plan(scene, task.scene, turned, task.success).images[-1]
        true.append(float(task.goal.loss(end[None])[0]))
    return list(SWEEP), predicted, true


if __name__ == "__main__":
    from afford.errors import exit_on_user_error

    exit_on_user_error(main)
