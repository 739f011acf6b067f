"""Write task variants a user would write: the paper's tasks mirrored left-right and shifted.

    python scripts/make_variants.py --out tasks/variants/candidates

Every position in a task moves: the start and goal scenes' objects, the goal crop's centre and
the success predicate's points and boxes; a mirror also turns yaws and quaternions. Whether a
variant keeps its task's challenge is for the oracle to say (`afford bench tasks --planner
oracle --tasks DIR`); only those it solves are kept in tasks/variants/, and that is decided
before any learned result is looked at.
"""

from __future__ import annotations

import argparse
import copy
import json
from pathlib import Path

PAPER = Path(__file__).resolve().parent.parent / "tasks" / "paper"
SHIFTS = {"shifted": (0.04, 0.02), "shifted-back": (-0.03, -0.02)}


def mirror_point(p: list[float]) -> list[float]:
    return [round(-p[0], 4), *p[1:]]


def transform(task: dict, point, yaw, quat, box) -> dict:
    """A copy of `task` with every pose and place mapped by the given functions."""
    out = copy.deepcopy(task)
    scenes = [out["scene"]] + ([out["goal"]["scene"]] if "scene" in out["goal"] else [])
    for scene in scenes:
        for o in scene["objects"]:
            o["pos"] = point(o["pos"])
            if "yaw" in o:
                o["yaw"] = yaw(o["yaw"])
            if "quat" in o:
                o["quat"] = quat(o["quat"])
    if "crop" in out["goal"]:
        out["goal"]["crop"]["centre"] = point(out["goal"]["crop"]["centre"])
    out["success"] = _predicate(out["success"], point, yaw, box)
    return out


def _predicate(node, point, yaw, box):
    if isinstance(node, list):
        return [_predicate(n, point, yaw, box) for n in node]
    if not isinstance(node, dict):
        return node
    out = {}
    for key, value in node.items():
        if key == "near":
            value = {**value, "to": point(value["to"])}
        elif key == "inside":
            value = {**value, "box": box(value["box"])}
        elif key == "yaw":
            value = {**value, "to": yaw(value["to"])}
        else:
            value = _predicate(value, point, yaw, box)
        out[key] = value
    return out


def mirrored(task: dict) -> dict:
    # Mirroring x: a yaw a becomes -a, a quaternion (w, x, y, z) becomes (w, x, -y, -z).
    def box(b):
        return [-b[2], b[1], -b[0], b[3]]

    return transform(task, mirror_point, lambda a: -a, lambda q: [q[0], q[1], -q[2], -q[3]], box)


def shifted(task: dict, dx: float, dy: float) -> dict:
    def point(p):
        return [round(p[0] + dx, 4), round(p[1] + dy, 4), *p[2:]]

    def box(b):
        return [b[0] + dx, b[1] + dy, b[2] + dx, b[3] + dy]

    return transform(task, point, lambda a: a, lambda q: q, box)


def main() -> None:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("--out", required=True, help="folder for the candidate task files")
    parser.add_argument("--tasks", default=str(PAPER), help="the tasks to vary (default: tasks/paper)")
    args = parser.parse_args()
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    for path in sorted(Path(args.tasks).glob("*.json")):
        task = json.loads(path.read_text())
        variants = {"mirrored": mirrored(task)}
        variants.update({name: shifted(task, dx, dy) for name, (dx, dy) in SHIFTS.items()})
        for name, variant in variants.items():
            variant["name"] = f"{task['name']}-{name}"
            variant["challenge"] = f"{task['challenge']} ({name} from the paper's task)"
            (out / f"{variant['name']}.json").write_text(json.dumps(variant, indent=2) + "\n")
    print(f"wrote {len(list(out.glob('*.json')))} candidates to {out}")


if __name__ == "__main__":
    main()
