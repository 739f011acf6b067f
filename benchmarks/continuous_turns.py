"""Continuous turn angles (paper V): the best of +-90 against angles optimised through the net.

    python benchmarks/continuous_turns.py --weights runs/wcont [--tasks tasks/continuous]
        [--out out/continuous] [--json]

For every task of the folder (goals that a quarter turn cannot reach), plans with the learned
planner twice: as the paper does (the search tries +90 and -90 for every turn) and with
`--optimise-turns` (the best plan with turns, its angles then found by gradient descent on
eq. (5) through the prediction net). Each plan is executed in the simulator and judged.
Prints both outcomes, the angle found and the planning time, and writes OUT/curves.png: eq.
(5) against the descent step, one line per restart, one panel per task. `--weights` should
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
    from afford.planning.learned import LearnedModel, load_learned
    from afford.planning.run import solve
    from afford.planning.tasks import load_task
    from afford.planning.tree import SearchConfig, search
    from afford.sim.scene import Scene

    learned = load_learned(args.weights)
    scene = Scene()
    files = sorted(Path(args.tasks).glob("*.json"))
    plain = SearchConfig(progress=False)
    rows, curves = [], {}
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
        tree = search(model, task.goal, task.max_steps, plain)
        with_turn = [n for n in tree.nodes if any(a.turn for a in n.plan)]
        if with_turn:
            best = min(with_turn, key=lambda n: n.loss)
            curves[task.name] = optimise_turns(model.net, model.image, best.plan, task.goal).curves
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    fig, axes = plt.subplots(1, max(len(curves), 1), figsize=(4.5 * max(len(curves), 1), 3.4), squeeze=False)
    for ax, (name, runs) in zip(axes[0], curves.items(), strict=False):
        for k, curve in enumerate(runs):
            ax.plot(curve, label=f"restart {k + 1}")
        ax.set(title=name, xlabel="gradient step", ylabel="eq. (5), predicted")
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


if __name__ == "__main__":
    main()
