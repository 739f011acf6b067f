"""`afford scene` and `afford demo`: the simulator on its own."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np


def _scene_from_args(args):
    from afford.sim.layout import random_layout
    from afford.sim.scene import Scene, load_scene_file

    scene = Scene()
    if args.load:
        scene.reset(load_scene_file(args.load), where=f"{Path(args.load).name}: ")
    else:
        scene.reset(
            random_layout(np.random.default_rng(args.seed)), check=False
        )  # overlap-free by construction
    return scene


def cmd_scene(args) -> int:
    """Render a scene, list its affordances, write RGB | depth | overlay."""
    from afford.sim.scene import save_scene_file, specs_to_json
    from afford.viz.draw import scene_picture

    scene = _scene_from_args(args)
    image = scene.observe()
    affs = scene.affordances()
    if args.out:
        Path(args.out).parent.mkdir(parents=True, exist_ok=True)
        scene_picture(image, affs, args.out)
    if args.save:
        save_scene_file(args.save, scene.specs())
    if args.json:
        objects = [
            {
                "name": o.name,
                "kind": o.kind,
                "pos": [round(float(v), 5) for v in o.pos],
                "quat": [round(float(v), 6) for v in o.quat],
            }
            for o in scene.objects()
        ]
        print(
            json.dumps(
                {
                    "objects": objects,
                    "affordances": [a.to_dict() for a in affs],
                    "scene": specs_to_json(scene.specs()),
                },
                indent=2,
            )
        )
    else:
        print(
            f"{len(scene.objects())} objects, {len(affs)} affordances"
            + (f"; picture: {args.out}" if args.out else "")
        )
        for a in affs:
            p = ", ".join(f"{v:+.3f}" for v in a.position)
            print(f"  {a.type:5s} at ({p}) angle {a.angle:5.1f}{' symmetric' if a.symmetric else ''}")
    scene.close()
    return 0


def cmd_demo(args) -> int:
    """A random scene, a few random affordances executed, a strip of the states."""
    from afford.sim.affordances import parametrise
    from afford.viz.draw import draw_affordances, hstack, label, to_pil

    scene = _scene_from_args(args)
    rng = np.random.default_rng(args.seed)
    panels = []
    for step in range(args.steps + 1):
        image = scene.observe()
        affs = parametrise(scene.affordances())
        if step == args.steps or not affs:
            panels.append(label(to_pil(image), "final" if affs else "final (no affordances)"))
            break
        a = affs[int(rng.integers(len(affs)))]
        panels.append(
            label(
                draw_affordances(to_pil(image), [a]),
                f"{step}: {a.type}" + (f" {a.turn:+g}" if a.turn else ""),
            )
        )
        scene.execute(a)
        print(f"step {step}: {a.type} at ({', '.join(f'{v:+.3f}' for v in a.position)}) angle {a.angle:.0f}")
    Path(args.out).parent.mkdir(parents=True, exist_ok=True)
    hstack(panels).save(args.out)
    print(f"picture: {args.out}")
    scene.close()
    return 0


def add_parsers(sub) -> None:
    s = sub.add_parser(
        "scene",
        help="render a scene and list its ground-truth affordances",
        description="Render a random scene (by seed) or a saved one, and list its affordances. "
        "Writes RGB | depth | affordance overlay (markers with gripper-angle lines: white where the "
        "angle matters, black where the affordance is symmetric; green grasp, cyan place, magenta turn).",
    )
    s.add_argument("--seed", type=int, default=0, help="random scene seed (ignored with --load)")
    s.add_argument("--load", metavar="SCENE.json", help="load a saved scene instead of a random one")
    s.add_argument("--save", metavar="SCENE.json", help="save the (settled) scene as JSON")
    s.add_argument("--out", metavar="FILE.png", help="write the picture here")
    s.add_argument("--json", action="store_true", help="print objects and affordances as JSON")
    s.set_defaults(func=cmd_scene)

    d = sub.add_parser(
        "demo",
        help="execute random affordances in a random scene and draw the states",
        description="Make a random scene, execute a few affordances drawn from its ground-truth "
        "list, and write a strip of the states with each executed affordance drawn.",
    )
    d.add_argument("--seed", type=int, default=0)
    d.add_argument("--load", metavar="SCENE.json", help="start from a saved scene")
    d.add_argument("--steps", type=int, default=4, help="number of affordances to execute")
    d.add_argument("--out", default="out/demo.png", metavar="FILE.png")
    d.set_defaults(func=cmd_demo)
