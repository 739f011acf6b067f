"""Learned planner speed on a 4-step paper task: kept node latents vs the chain rerun from the root.

    python benchmarks/learned_planning.py [--task tasks/paper/04-counterbalance-ball-first.json]
                                          [--weights DIR] [--threads 2] [--json]

Plans the task twice with the same nets: once keeping each node's latent, memory trace and
image (a child costs one P and one D step), once rerunning every child's whole chain from the
root image (the authors' planner). Both must choose the same plan.
"""

from __future__ import annotations

import argparse
import json

import torch

from afford.planning.learned import LearnedModel
from afford.planning.strategies import search
from afford.planning.tasks import load_task
from afford.planning.tree import SearchConfig
from afford.shipped import Nets
from afford.sim.scene import Scene


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--task", default="tasks/paper/04-counterbalance-ball-first.json")
    ap.add_argument("--weights", default=None)
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--json", action="store_true")
    args = ap.parse_args()
    torch.set_num_threads(args.threads)
    nets = Nets(args.weights)
    recognizer, predictor = nets.recognizer, nets.predictor
    scene = Scene()
    task = load_task(args.task, scene)
    result = {"task": task.name, "max_steps": task.max_steps, "threads": args.threads}
    plans = {}
    for mode, rerun in (("kept_latents", False), ("rerun_from_root", True)):
        scene.reset(task.scene)
        model = LearnedModel(scene.observe(), recognizer, predictor, rerun_from_root=rerun)
        r = search(model, task.goal, task.max_steps, SearchConfig(progress=False))
        plans[mode] = [a.to_dict() for a in r.plan]
        result[mode] = {"seconds": round(r.seconds, 2), "nodes": len(r.nodes), "p_d_steps": model.p_steps}
    result["speedup"] = round(result["rerun_from_root"]["seconds"] / result["kept_latents"]["seconds"], 2)
    result["same_plan"] = plans["kept_latents"] == plans["rerun_from_root"]
    if args.json:
        print(json.dumps(result, indent=2))
        return
    for mode in ("kept_latents", "rerun_from_root"):
        r = result[mode]
        print(f"{mode:16s} {r['seconds']:7.2f} s  {r['nodes']} nodes  {r['p_d_steps']} P+D steps")
    print(f"speed-up from keeping latents: {result['speedup']:.2f}x; same plan: {result['same_plan']}")


if __name__ == "__main__":
    from afford.errors import exit_on_user_error

    exit_on_user_error(main)
