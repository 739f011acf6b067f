"""Simulator speed on one core: physics steps/s, RGBD frames/s, affordance executions/s.

Run: python benchmarks/sim_speed.py [--scenes N] [--json]
Executions are random ground-truth affordances in random scenes, settle included (the
target is at least 10 executions/s per core).
"""

from __future__ import annotations

import argparse
import json
import os
import time

os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("MUJOCO_GL", "egl")  # before mujoco is imported

import mujoco  # noqa: E402
import numpy as np  # noqa: E402

from afford.sim.affordances import parametrise  # noqa: E402
from afford.sim.layout import random_layout  # noqa: E402
from afford.sim.scene import Scene  # noqa: E402


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--scenes", type=int, default=25)
    ap.add_argument("--json", action="store_true")
    args = ap.parse_args()
    scene = Scene()
    rng = np.random.default_rng(0)

    scene.reset(random_layout(np.random.default_rng(1)))
    n = 5000
    t = time.perf_counter()
    for _ in range(n):
        mujoco.mj_step(scene.model, scene.data)
    steps_per_s = n / (time.perf_counter() - t)

    scene.observe()
    t = time.perf_counter()
    for _ in range(200):
        scene.observe()
    frames_per_s = 200 / (time.perf_counter() - t)

    executions, detections = 0, 0
    exec_time = detect_time = 0.0
    sim_steps = 0
    for _ in range(args.scenes):
        scene.reset(random_layout(rng))
        for _ in range(4):
            t = time.perf_counter()
            affs = parametrise(scene.affordances())
            detect_time += time.perf_counter() - t
            detections += 1
            if not affs:
                break
            t = time.perf_counter()
            result = scene.execute(affs[int(rng.integers(len(affs)))])
            exec_time += time.perf_counter() - t
            sim_steps += result.steps
            executions += 1
    out = {
        "physics_steps_per_s": round(steps_per_s),
        "rgbd_frames_per_s": round(frames_per_s, 1),
        "executions_per_s": round(executions / exec_time, 2),
        "mean_steps_per_execution": round(sim_steps / executions),
        "affordance_detections_per_s": round(detections / detect_time, 1),
        "executions": executions,
    }
    scene.close()
    if args.json:
        print(json.dumps(out))
    else:
        for k, v in out.items():
            print(f"{k:32s} {v}")


if __name__ == "__main__":
    from afford.errors import exit_on_user_error

    exit_on_user_error(main)
