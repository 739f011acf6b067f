"""Where along a block resting off its centre does a place tip it: the simulator and the dynamics.

    python benchmarks/tipping.py --weights src/afford/weights/objects/dynamics.safetensors \
        [--weights runs/dyn-seed1/best.safetensors ...] [--start true|perceived|both] \
        [--perception FILE] \
        [--out docs/objects-tipping.png] [--json]

The paper's counterweight tasks (04, 05) turn on whether a place near the end of a block that
rests off its centre tips it, alone and with a counterweight already on the other end. This
sweeps that place along the block in both tasks' scenes, from three states: after the first
grasp of the oracle's plan (the first object placed alone), after the other object's grasp
(the other order: the second object alone), and after the plan's first three steps (the second
object beside the first). Each place is run by the simulator from the true state and predicted
by each dynamics net (its likeliest outcome) from the true state or from the objects the
perception net sees in the state's image, as a planner does. It prints, per net, start and
sweep, the share of places where net and simulator agree on whether the block tips (its long
axis turns by more than TIPPED_DEG) and the tilt each gives at the block's two ends (where the
tasks place); with --out, draws the block's tilt against the place's position. The steps of
each task are the oracle's plan (`afford plan --planner oracle`), written here.
"""

from __future__ import annotations

import argparse
import json
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from afford.errors import UserError

TIPPED_DEG = 10.0  # the block's long axis turned by more than this: it tipped
SWEEP = np.round(np.arange(-0.12, 0.1201, 0.01), 3)  # place x, metres (the block is 24 cm long)
TASKS = Path(__file__).resolve().parents[1] / "tasks" / "paper"

# The oracle's plans of the two tasks (`afford plan --task T --planner oracle --json`): the
# first grasp, the first place, the second grasp and the second place.
PLANS = {
    "04-counterbalance-ball-first": (
        ("grasp", (0.07, 0.19, 0.02499)),
        ("place", (0.08999, 0.3, 0.11)),
        ("grasp", (-0.05, 0.19, 0.0425)),
        ("place", (-0.08999, 0.3, 0.11001)),
    ),
    "05-counterbalance-cup-first": (
        ("grasp", (0.07, 0.19, 0.0425)),
        ("place", (-0.08999, 0.3, 0.11)),
        ("grasp", (-0.05, 0.19, 0.02499)),
        ("place", (0.08999, 0.3, 0.11001)),
    ),
}


@dataclass
class Sweep:
    task: str
    start: str  # the nets' start state: "true" or "perceived"
    what: str  # which object is placed, on what
    step: int  # the plan's place whose row is swept: 1 (the first place) or 3 (the second)
    x: np.ndarray  # (n,) place positions along the block
    tilt: dict[str, np.ndarray]  # model name -> (n,) the block's tilt after, degrees


def affordance(kind: str, position) -> np.ndarray:
    from afford.sim.affordance import Affordance, encode_affordance

    return encode_affordance(Affordance(kind, tuple(position), 0.0, True))


def block_tilt(before: np.ndarray, after: np.ndarray, block: int) -> np.ndarray:
    """(n,) degrees between the block's long axis before and after; 90 where it left the table."""
    from afford.objects.state import quat_axes

    _, a0 = quat_axes(before[block, 3:7].astype(float))
    gone = np.isnan(after[:, block, 0])
    _, a1 = quat_axes(np.nan_to_num(after[:, block, 3:7].astype(float), nan=1.0))
    cos = np.clip(np.abs(a1 @ a0), 0.0, 1.0)
    return np.where(gone, 90.0, np.degrees(np.arccos(cos)))


def start_states(scene, task: str) -> dict[str, tuple[np.ndarray, int, np.ndarray, int]]:
    """Before each swept place: the state (poses, held slot), its image, and the plan's step
    whose place height and row it takes. The first object alone (the plan's order), the second object
    alone (the other order: its grasp first), and the second beside the first."""
    from afford.data.draws import pose_array
    from afford.objects.simulated import simulate
    from afford.planning.tasks import load_task

    specs = load_task(TASKS / f"{task}.json", scene).scene
    scene.reset(specs)
    start = pose_array(scene)

    def run(poses, held, steps):
        for kind, position in steps:
            out = simulate(scene, poses[None], np.array([held]), affordance(kind, position)[None])
            poses, held = out.poses[0, 0], int(out.held[0, 0])
            if (kind == "grasp") != (held >= 0):  # the arm could not carry the plan's step out
                raise UserError(f"{task}: the oracle's {kind} at {position} did not execute")
        return poses, held, scene.observe()

    plan = PLANS[task]
    first, second = plan[0], plan[2]
    return {
        "first alone": (*run(start, -1, [first]), 1),
        "second alone": (*run(start, -1, [second]), 3),
        "second beside the first": (*run(start, -1, plan[:3]), 3),
    }


def sweep(scene, task: str, models: dict, perception=None) -> list[Sweep]:
    """The sweeps of one task; with `perception`, the nets start from the objects it sees in
    each state's image (as in planning), the simulator from the true state."""
    from afford.objects.perceive import perceive, to_state
    from afford.objects.simulated import simulate
    from afford.objects.state import KINDS, SLOT_KIND

    block = next(s for s in range(len(SLOT_KIND)) if KINDS[SLOT_KIND[s]] == "block")
    result = []
    for what, (poses, held, image, step) in start_states(scene, task).items():
        _, (_, y, z) = PLANS[task][step]
        actions = np.stack([affordance("place", (x, y, z)) for x in SWEEP])
        n = len(SWEEP)
        true_after = simulate(scene, np.repeat(poses[None], n, 0), np.full(n, held), actions).poses[:, 0]
        tilt = {"simulator": block_tilt(poses, true_after, block)}
        seen, seen_held = poses, held
        if perception is not None:
            seen, seen_held = to_state(perceive(perception, image[None].astype(np.float32))[0])
        for name, model in models.items():
            after, _ = model.outcomes(np.repeat(seen[None], n, 0), np.full(n, seen_held), actions).likeliest()
            tilt[name] = block_tilt(seen, after, block)
        start = "true" if perception is None else "perceived"
        result.append(Sweep(task, start, what, step, SWEEP.copy(), tilt))
    return result


def agreement(s: Sweep, name: str) -> float:
    truth = s.tilt["simulator"] > TIPPED_DEG
    return float(np.mean((s.tilt[name] > TIPPED_DEG) == truth))


def draw(sweeps: list[Sweep], out: str) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    columns = 3  # per task and start: the first object alone, the second alone, the second beside
    rows = len(sweeps) // columns
    fig, axes = plt.subplots(rows, columns, figsize=(4.2 * columns, 3.0 * rows), sharey=True, squeeze=False)
    for ax, s in zip(axes.flat, sweeps, strict=True):
        for name, tilt in s.tilt.items():
            style = {"color": "black", "linewidth": 2.5} if name == "simulator" else {"linewidth": 1.2}
            ax.plot(s.x * 100, tilt, label=name, **style)
        for step in (1, 3):  # where the plan places each object
            ax.axvline(PLANS[s.task][step][1][0] * 100, color="grey", linestyle=":", linewidth=1)
        ax.axhline(TIPPED_DEG, color="grey", linestyle="--", linewidth=0.8)
        ax.set_title(f"{s.task[:2]}, {s.start} start: {s.what}", fontsize=10)
        ax.set_xlabel("place along the block (cm)")
    for row in axes:
        row[0].set_ylabel("block's tilt after (degrees)")
    axes.flat[-1].legend(fontsize=7, loc="upper right")
    fig.tight_layout()
    Path(out).parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(out, dpi=110)


def main() -> int:
    from afford.errors import exit_on_user_error

    parser = argparse.ArgumentParser(
        description=__doc__.split("\n\n")[2], formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument(
        "--weights", action="append", required=True, metavar="FILE", help="a dynamics net; repeat for more"
    )
    parser.add_argument(
        "--start",
        choices=("true", "perceived", "both"),
        default="both",
        help="the nets' start states: the true ones, the objects the shipped perception net sees in "
        "each state's image (as in planning), or both (default)",
    )
    parser.add_argument(
        "--perception",
        metavar="FILE",
        help="the perception net of the perceived starts (default: the shipped one)",
    )
    parser.add_argument("--out", metavar="FILE.png", help="draw the sweeps here")
    parser.add_argument("--json", action="store_true", help="the figures as JSON")
    args = parser.parse_args()
    exit_on_user_error(lambda: run(args))
    return 0


def label(weights: str) -> str:
    """A net's name in the table: the shipped one, a run's folder, or the file's name."""
    from afford.shipped import OBJECTS

    path = Path(weights).resolve()
    if path.parent == OBJECTS:
        return "shipped net"
    return path.parent.name if path.name == "best.safetensors" else path.stem


def run(args) -> None:
    from afford.objects.train import load_dynamics
    from afford.sim.scene import Scene

    labels = [label(w) for w in args.weights]
    if len(set(labels)) < len(labels):
        raise UserError(f"two weights files share a name in the table: {', '.join(labels)}")
    nets = {name: load_dynamics(w) for name, w in zip(labels, args.weights, strict=True)}
    models = dict(nets)
    scene = Scene()
    from afford.objects.perception_train import load_perception
    from afford.shipped import Nets

    seeing = load_perception(args.perception) if args.perception else Nets().perception
    starts = {"true": [None], "perceived": [seeing]}
    starts["both"] = starts["true"] + starts["perceived"]
    sweeps = [
        s for seen_by in starts[args.start] for task in PLANS for s in sweep(scene, task, models, seen_by)
    ]
    rows = [
        {
            "task": s.task,
            "start": s.start,
            "place": s.what,
            "model": name,
            "agreement": agreement(s, name),
            "tilt_at_left_end": float(np.interp(-0.09, s.x, s.tilt[name])),
            "tilt_at_right_end": float(np.interp(0.09, s.x, s.tilt[name])),
        }
        for s in sweeps
        for name in s.tilt
    ]
    if args.out:
        draw(sweeps, args.out)
    if args.json:
        print(json.dumps({"tipped_deg": TIPPED_DEG, "rows": rows}, indent=2))
    else:
        print(
            f"{'task':30s} {'start':9s} {'place':24s} {'model':18s} {'agree':>6s} {'tilt at -9 / +9 cm':>19s}"
        )
        for r in rows:
            tilt = f"{r['tilt_at_left_end']:.1f} / {r['tilt_at_right_end']:.1f}"
            print(
                f"{r['task']:30s} {r['start']:9s} {r['place']:24s} {r['model']:18s} {r['agreement']:6.2f} "
                f"{tilt:>19s}"
            )


if __name__ == "__main__":
    raise SystemExit(main())
