"""Uncertain outcomes (paper V): risk-averse against plain plan scores, over perturbed executions.

    python benchmarks/uncertain_outcomes.py [--weights DIR] [--tasks tasks/uncertain]
        [--perturb 0.005,3] [--executions 20] [--risk 1.0] [--out out/uncertain] [--json]

For every task of the folder (places near a tipping edge), plans three ways: the learned
planner (one prediction net), the ensemble with risk 0 (the members' mean loss: the plain
score) and the ensemble risk-averse (`--risk`). Each plan is then executed `--executions`
times, every time from its own perturbed start (`sim/perturb.py`; the same draws for every
planner). Prints the success rates and writes OUT/spread.png: per task, the ensemble's best
predicted end states (mean image and per-pixel spread), each with its mean loss, spread, and
the share of perturbed executions of its plan that succeed.
"""

from __future__ import annotations

import argparse
import json
from dataclasses import replace
from pathlib import Path

CANDIDATES = 4  # end states drawn per task


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument(
        "--weights", metavar="DIR", help="a weights folder with ensemble/ (default: the shipped one)"
    )
    ap.add_argument("--tasks", default="tasks/uncertain", metavar="DIR")
    ap.add_argument("--perturb", default="0.005,3", metavar="METRES,DEGREES")
    ap.add_argument("--executions", type=int, default=20)
    ap.add_argument(
        "--risk", type=float, default=None, help="the risk-averse weight (default: the planner's)"
    )
    ap.add_argument("--out", default="out/uncertain", metavar="DIR")
    ap.add_argument("--json", action="store_true")
    args = ap.parse_args()

    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import numpy as np

    from afford.planning.run import PlannerConfig, execute_perturbed, perturbed_successes, solve
    from afford.planning.strategies import search
    from afford.planning.tasks import load_task
    from afford.planning.tree import SearchConfig
    from afford.planning.uncertain import EnsembleModel
    from afford.shipped import Nets
    from afford.sim.perturb import Perturbation
    from afford.sim.scene import Scene

    perturbation = Perturbation(*[float(v) for v in args.perturb.split(",")])
    nets = Nets(args.weights)
    quiet = SearchConfig(progress=False)
    averse = PlannerConfig(search=quiet) if args.risk is None else PlannerConfig(search=quiet, risk=args.risk)
    ways = {
        "learned": ("learned", averse),
        "ensemble, risk 0": ("ensemble", replace(averse, risk=0.0)),
        f"ensemble, risk {averse.risk:g}": ("ensemble", averse),
    }
    scene = Scene()
    files = sorted(Path(args.tasks).glob("*.json"))
    rows, panels = [], []
    for f in files:
        task = load_task(f, scene)
        row = {"task": task.name}
        for label, (planner, config) in ways.items():
            o = solve(task, planner, scene, config, nets)
            execute_perturbed(o, task, scene, perturbation, args.executions)
            row[label] = {
                "nominal": o.success,
                "perturbed_success_rate": sum(o.perturbed) / len(o.perturbed),
                "plan": [a.type + str(tuple(round(v, 3) for v in a.position)) for a in o.plan or ()],
                "spread": o.spread,
            }
        rows.append(row)
        # The picture: the ensemble's best end states (by mean loss), their spread, their fate.
        scene.reset(task.scene)
        model = EnsembleModel(scene.observe(), nets.recognizer, nets.members, 0.0)
        tree = search(model, task.goal, task.max_steps, averse.search)
        ends = sorted((n for n in tree.nodes if n.depth == task.max_steps), key=lambda n: n.loss)
        shown, seen = [], set()
        for n in ends:
            key = tuple(round(v, 2) for a in n.plan for v in a.position)
            if key in seen:
                continue
            seen.add(key)
            wins = perturbed_successes(n.plan, task, scene, perturbation, args.executions)
            shown.append((n, float(np.mean(wins))))
            if len(shown) == CANDIDATES:
                break
        panels.append((task.name, shown))
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    cols = max(len(s) for _, s in panels)
    fig, axes = plt.subplots(2 * len(panels), cols, figsize=(2.9 * cols, 5.6 * len(panels)), squeeze=False)
    top = max(float(n.state.pixel_spread.max()) for _, s in panels for n, _ in s)
    for t, (name, shown) in enumerate(panels):
        for c in range(cols):
            for ax in (axes[2 * t, c], axes[2 * t + 1, c]):
                ax.axis("off")
            if c >= len(shown):
                continue
            n, rate = shown[c]
            place = n.plan[-1].position
            axes[2 * t, c].imshow(np.clip(n.image[..., :3], 0, 1))
            axes[2 * t, c].set_title(
                f"{name if c == 0 else ''}\n{n.plan[-1].type} at x {place[0]:+.2f} y {place[1]:.2f}\n"
                f"loss {n.loss:.4f} spread {n.spread:.4f}",
                fontsize=7,
                loc="left",
            )
            im = axes[2 * t + 1, c].imshow(n.state.pixel_spread, cmap="magma", vmin=0, vmax=top)
            axes[2 * t + 1, c].set_title(f"spread; {rate:.0%} succeed perturbed", fontsize=7)
    fig.colorbar(im, ax=axes.ravel().tolist(), shrink=0.3, label="std over members (mean over RGBD)")
    fig.savefig(out / "spread.png", dpi=100)
    if args.json:
        print(json.dumps(rows, indent=2))
        return
    for r in rows:
        cells = "   ".join(
            f"{label}: {r[label]['perturbed_success_rate']:.0%}"
            + ("" if r[label]["nominal"] else " (fails unperturbed)")
            for label in ways
        )
        print(f"{r['task']:30s} {cells}")
    for label in ways:
        rate = np.mean([r[label]["perturbed_success_rate"] for r in rows])
        print(f"{label}: {rate:.0%} of perturbed executions succeed over the tasks")
    print(f"picture: {out / 'spread.png'}")


if __name__ == "__main__":
    from afford.errors import exit_on_user_error

    exit_on_user_error(main)
