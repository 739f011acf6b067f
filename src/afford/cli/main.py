"""The `afford` command line. Each subcommand is a small function; bad input ends in one line."""

from __future__ import annotations

import argparse
import json
import os
import sys
from pathlib import Path

import numpy as np

from afford.cli.errors import CLIError


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


def _outcome_line(o) -> str:
    plan = "-" if o.plan is None else " > ".join(a.type + (f"{a.turn:+g}" if a.turn else "") for a in o.plan)
    return f"{'solved' if o.success else 'FAILED'}: {plan}"


def cmd_plan(args) -> int:
    """Plan a task file, execute the plan in the simulator, draw it (paper Fig. 8)."""
    from afford.planning.run import USES_NETS, execute_perturbed, solve
    from afford.planning.tasks import load_task
    from afford.sim.scene import Scene
    from afford.viz.plan import plan_strip

    scene = Scene()
    task = load_task(args.task, scene)
    perturbation = _perturbation(args)
    learned = _learned(args) if args.planner in USES_NETS else None
    outcome = solve(task, args.planner, scene, _search_config(args, progress=not args.json), learned)
    if perturbation is not None:
        execute_perturbed(outcome, task, scene, perturbation, args.executions)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    picture = out / f"{task.name}-{args.planner}.png"
    plan_strip(outcome, task.goal, picture)
    record = outcome.to_dict() | {"picture": str(picture)}
    (out / f"{task.name}-{args.planner}.json").write_text(json.dumps(record, indent=2) + "\n")
    if args.json:
        print(json.dumps(record, indent=2))
    else:
        print(f"{task.name} ({args.planner}) {_outcome_line(outcome)}")
        print(
            f"  {outcome.nodes} nodes, {outcome.seconds:.1f} s planning"
            + (f"; {outcome.reason}" if outcome.reason else "")
        )
        if outcome.perturbed:
            rate = sum(outcome.perturbed) / len(outcome.perturbed)
            print(
                f"  perturbed executions: {sum(outcome.perturbed)}/{len(outcome.perturbed)} "
                f"succeed ({rate:.0%})"
            )
        print(f"  picture: {picture}")
    scene.close()
    return 0 if outcome.success else 1


def cmd_bench_tasks(args) -> int:
    """Every task of a folder with one planner: a table (paper IV.C, Fig. 8)."""
    from afford.planning.run import USES_NETS, execute_perturbed, solve
    from afford.planning.tasks import load_task
    from afford.sim.scene import Scene
    from afford.viz.plan import plan_strip

    files = sorted(Path(args.tasks).glob("*.json"))
    if not files:
        raise CLIError(f"{args.tasks}: no task files (*.json) there")
    planners = _planners(args.planner)
    perturbation = _perturbation(args)
    learned = _learned(args) if any(p in USES_NETS for p in planners) else None
    config = _search_config(args, progress=False)
    scene = Scene()
    report = {}
    for planner in planners:
        rows = []
        for f in files:
            task = load_task(f, scene)
            live = not args.json and sys.stdout.isatty()
            if live:
                print(f"{task.name} ...", end="", flush=True)
            o = solve(task, planner, scene, config, learned)
            if perturbation is not None:
                execute_perturbed(o, task, scene, perturbation, args.executions)
            if args.out:
                plan_strip(o, task.goal, Path(args.out) / f"{task.name}-{planner}.png")
            rows.append(o.to_dict())
            if not args.json:
                back = "\r" if live else ""
                print(f"{back}{task.name:32s} {_outcome_line(o)}  [{o.nodes} nodes, {o.seconds:.1f} s]")
                if o.reason:
                    print(f"{'':32s} {o.reason}")
                if o.perturbed:
                    print(f"{'':32s} perturbed: {sum(o.perturbed)}/{len(o.perturbed)} executions succeed")
        solved = sum(r["solved"] for r in rows)
        report[planner] = {"solved": solved, "tasks": rows}
        if perturbation is not None:
            rates = [r["perturbed_success_rate"] for r in rows]
            report[planner]["perturbed_success_rate"] = round(sum(rates) / len(rates), 4)
            if not args.json:
                print(
                    f"{planner}: {sum(rates) / len(rates):.0%} of perturbed executions succeed, "
                    "over the tasks"
                )
        expected = [r["success_rate"] for r in rows if "success_rate" in r]
        if expected:
            report[planner]["expected_solved"] = round(sum(expected), 3)
        if not args.json:
            fair = f" (over its equally short plans: {sum(expected):.2f} expected)" if expected else ""
            print(f"{planner}: {solved}/{len(rows)} tasks solved{fair}")
    if args.json:
        print(json.dumps(report, indent=2))
    scene.close()
    return 0


def cmd_bench_random(args) -> int:
    """Random goals (random scenes, 1 to --max-steps random executions), every planner: success
    rates with 95% intervals, the tasks planned over parallel workers."""
    from tqdm import tqdm

    from afford.planning.random_bench import BenchSpec, run, summarise
    from afford.planning.run import USES_NETS

    if args.n < 1:
        raise CLIError("--n must be at least 1")
    if args.workers < 1:
        raise CLIError("--workers must be at least 1")
    if args.time_limit is not None and args.time_limit <= 0:
        raise CLIError("--time-limit must be positive (seconds)")
    if not 1 <= args.min_steps <= args.max_steps:
        raise CLIError("--min-steps must be at least 1 and at most --max-steps")
    planners = _planners(args.planner)
    if any(p in USES_NETS for p in planners):
        _learned(args)  # a missing weights folder is one line here, not a worker's traceback
    threads = max(1, (os.cpu_count() or 1) // args.workers)
    spec = BenchSpec(
        args.max_steps,
        planners,
        args.weights,
        args.time_limit,
        threads,
        args.min_steps,
        _search_config(args, progress=False),
    )
    rows = []
    with tqdm(total=args.n, desc="bench random", unit="task", disable=args.json) as bar:
        for row in run(spec, args.n, args.seed, args.workers):
            rows.append(row)
            bar.update(1)
    summary = summarise(rows, planners)
    if args.out:
        out = Path(args.out)
        out.parent.mkdir(parents=True, exist_ok=True)
        record = {
            "n": len(rows),
            "first_seed": args.seed,
            "min_steps": args.min_steps,
            "max_steps": args.max_steps,
            "search": args.search,
            "summary": summary,
        }
        out.write_text(json.dumps(record | {"tasks": rows}, indent=2) + "\n")
    if args.json:
        print(
            json.dumps({"n": len(rows), "first_seed": args.seed, "summary": summary, "tasks": rows}, indent=2)
        )
        return 0
    for p in planners:
        s = summary[p]
        cut = f", {s['truncated']} cut by the time limit" if s["truncated"] else ""
        ratio = f"; {s['of_oracle']:.2f} x oracle" if "of_oracle" in s else ""
        print(
            f"{p:9s} {s['success']:.2f} [{s['ci95'][0]:.2f}, {s['ci95'][1]:.2f}] success over {len(rows)} "
            f"random tasks of {args.min_steps}-{args.max_steps} steps ({s['seconds']:.1f} s planning and "
            f"{s['nodes']:.0f} states each{cut}){ratio}"
        )
    return 0


def cmd_diagnose(args) -> int:
    """Why the learned planner fails a task: the oracle's plan replayed through the nets."""
    from tqdm import tqdm

    from afford.planning.diagnose import diagnose
    from afford.planning.tasks import load_task
    from afford.sim.scene import Scene

    files = []
    for given in args.tasks:
        path = Path(given)
        found = sorted(path.glob("*.json")) if path.is_dir() else [path]
        if not found:
            raise CLIError(f"{given}: no task files (*.json) there")
        files += found
    learned = _learned(args)
    scene = Scene()
    out = []
    for f in tqdm(files, desc="diagnose", unit="task", disable=args.json or len(files) == 1):
        d = diagnose(load_task(f, scene), scene, learned)
        out.append(d.to_dict())
        if not args.json:
            tqdm.write(d.describe())
    if args.json:
        print(json.dumps(out, indent=2))
    scene.close()
    return 0


def _learned(args):
    """The trained nets for the learned planner: --weights, or the ones shipped in the package."""
    from afford.shipped import load_learned

    try:
        return load_learned(args.weights)
    except FileNotFoundError as e:
        raise CLIError(str(e)) from None


def _planners(given: str) -> tuple[str, ...]:
    from afford.planning.run import PLANNERS

    if given == "all":
        return PLANNERS
    names = tuple(n.strip() for n in given.split(","))
    unknown = [n for n in names if n not in PLANNERS]
    if unknown:
        raise CLIError(
            f"unknown planner {unknown[0]!r}; expected {', '.join(PLANNERS)} or all, or a comma list"
        )
    return names


def _add_search_arguments(parser, max_nodes: bool = True) -> None:
    """How the tree grows: the paper's breadth-first search, or a guided one (paper V)."""
    from afford.planning.strategies import STRATEGIES
    from afford.planning.tree import GUIDED_BUDGET, SearchConfig

    parser.add_argument(
        "--search",
        choices=tuple(STRATEGIES),
        default="breadth",
        help="breadth: every branch, the paper's (default); beam: per depth the --beam-width states "
        "closest to the goal (eq. 5) are expanded; best-first: the closest open states of any depth "
        "first. Hybrid planners search this way when the world model rejects every canonical plan",
    )
    parser.add_argument(
        "--beam-width",
        type=int,
        default=SearchConfig.beam_width,
        metavar="K",
        help="beam: states kept per depth",
    )
    parser.add_argument(
        "--budget",
        type=int,
        metavar="N",
        help=f"the most states grown (default: {GUIDED_BUDGET:,} for beam and best-first, none for breadth)",
    )
    parser.add_argument(
        "--accept",
        type=float,
        default=SearchConfig.accept,
        metavar="SHARE",
        help="hybrid planners: a canonical plan is kept when its predicted outcome removes at least this "
        f"share of the start's goal loss, eq. 5 (default {SearchConfig.accept})",
    )
    parser.add_argument(
        "--optimise-turns",
        action="store_true",
        help="learned planner: optimise the turn angles of the best plan with turns by gradient descent "
        "on eq. 5 through the prediction net (paper V), keeping it when it comes closer; needs a "
        "prediction net trained on continuous turns (afford generate --turn-angles continuous)",
    )
    parser.add_argument(
        "--risk",
        type=float,
        default=SearchConfig.risk,
        metavar="W",
        help="ensemble planner: a plan scores the members' mean goal loss (eq. 5) plus W standard "
        f"deviations of it over the members: risk-averse (default {SearchConfig.risk}); 0: the mean alone",
    )
    if max_nodes:
        parser.add_argument(
            "--max-nodes", type=int, default=SearchConfig.max_nodes, metavar="N", help=MAX_NODES_HELP
        )


def _add_perturb_arguments(parser) -> None:
    """Executions from perturbed starts (sim/perturb.py): outcomes that succeed only sometimes."""
    from afford.sim.perturb import Perturbation

    parser.add_argument(
        "--perturb",
        type=str,
        metavar="METRES[,DEGREES]",
        help="after planning, execute the plan --executions times, each time with every pile of objects "
        "shifted by a Gaussian of this standard deviation (and turned by DEGREES, default "
        f"{Perturbation.yaw:g}), and report the share that succeed",
    )
    parser.add_argument(
        "--executions", type=int, default=20, metavar="N", help="perturbed executions per plan (default 20)"
    )


def _perturbation(args):
    """The --perturb of the command line, or None."""
    from afford.sim.perturb import Perturbation

    if not getattr(args, "perturb", None):
        return None
    try:
        sizes = [float(v) for v in args.perturb.split(",")]
        if len(sizes) > 2:
            raise ValueError
        perturbation = Perturbation(*sizes)
    except ValueError:
        raise CLIError(f"--perturb {args.perturb!r}: expected METRES or METRES,DEGREES, both >= 0") from None
    if args.executions < 1:
        raise CLIError("--executions must be at least 1")
    return perturbation


def _search_config(args, progress: bool):
    from afford.planning.tree import SearchConfig

    if args.beam_width < 1:
        raise CLIError("--beam-width must be at least 1")
    if args.budget is not None and args.budget < 1:
        raise CLIError("--budget must be at least 1 state")
    if not 0 < args.accept < 1:
        raise CLIError("--accept must lie between 0 and 1")
    max_nodes = getattr(args, "max_nodes", SearchConfig.max_nodes)
    return SearchConfig(
        progress=progress,
        max_nodes=max_nodes or None,
        strategy=args.search,
        beam_width=args.beam_width,
        budget=args.budget,
        accept=args.accept,
        optimise_turns=args.optimise_turns,
        risk=args.risk,
    )


PLANNERS_HELP = (
    "one planner (oracle, symbolic, learned, hybrid, hybrid-oracle, ensemble), several as a comma list, "
    "or all"
)
MAX_NODES_HELP = (
    "refuse to grow a tree past this many states, with the estimate, before growing the depth that "
    "would pass it (default 20,000; 0: no limit; the paper's tasks need at most ~700)"
)


def build_parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(
        prog="afford",
        description="Plan action sequences by recognising affordances in predicted futures.",
    )
    sub = p.add_subparsers(dest="command", required=True)

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

    from afford.planning.run import PLANNERS

    pl = sub.add_parser(
        "plan",
        help="plan a task file, execute the plan, check the goal",
        description="Plan a task (a JSON task file, see tasks/paper/) by tree search over affordances, "
        "execute the plan in the simulator and check the task's success predicate. Planners: oracle (the "
        "simulator as a perfect world model, paper II.D search), symbolic (canonical effects only, "
        "breadth-first), learned (the paper's method: the same search with the trained recognition and "
        "prediction nets), hybrid (paper V: the symbolic planner's canonical plans, each checked by the "
        "learned nets against the goal; the search when all are rejected), hybrid-oracle (the same, "
        "checked by the simulator). Writes a picture like the paper's Fig. 8 and a JSON record. Exit "
        "status 1 when the executed plan misses the goal.",
    )
    pl.add_argument("--task", required=True, metavar="TASK.json")
    pl.add_argument("--planner", choices=PLANNERS, default="oracle")
    pl.add_argument("--out", default="out/plan", metavar="DIR", help="where the picture and record go")
    pl.add_argument("--json", action="store_true", help="print the record as JSON")
    _add_perturb_arguments(pl)
    pl.add_argument(
        "--weights",
        "--run-dir",
        metavar="DIR",
        help="learned planner: a folder with recognition.safetensors and prediction.safetensors, or with "
        "recognition/ and prediction/ training runs (default: the weights shipped in the package)",
    )
    _add_search_arguments(pl)
    pl.set_defaults(func=cmd_plan)

    b = sub.add_parser("bench", help="benchmarks", description="Benchmarks over a set of tasks.")
    bsub = b.add_subparsers(dest="bench", required=True)
    bt = bsub.add_parser(
        "tasks",
        help="plan and execute every task of a folder, print a table",
        description="Plan every task file in a folder with one planner, execute each plan, and print "
        "solved / plan / plan length / nodes / planning seconds per task.",
    )
    bt.add_argument("--planner", default="oracle", metavar="NAME[,NAME]|all", help=PLANNERS_HELP)
    bt.add_argument(
        "--weights", "--run-dir", metavar="DIR", help="learned planner's weights (see afford plan)"
    )
    bt.add_argument("--tasks", default="tasks/paper", metavar="DIR")
    bt.add_argument("--out", metavar="DIR", help="also write each plan's picture here")
    bt.add_argument("--json", action="store_true")
    _add_perturb_arguments(bt)
    _add_search_arguments(bt)
    bt.set_defaults(func=cmd_bench_tasks)

    br = bsub.add_parser(
        "random",
        help="random goals made by executing random affordances; success rates per planner",
        description="Random tasks nobody tuned by hand: a random scene, 1 to --max-steps random affordance "
        "executions, the goal a crop of the final image around what changed; success = every object within "
        "3 cm of its goal position. Prints each planner's success rate with a Wilson 95% interval; the "
        "symbolic planner scores the share of its equally short canonical plans that succeed.",
    )
    br.add_argument("--n", type=int, default=50, help="number of tasks (default 50)")
    br.add_argument("--seed", type=int, default=0)
    br.add_argument("--max-steps", type=int, default=4)
    br.add_argument("--min-steps", type=int, default=1, help="fewest random executions a goal is made of")
    br.add_argument("--planner", default="all", metavar="NAME[,NAME]|all", help=PLANNERS_HELP)
    br.add_argument(
        "--weights", "--run-dir", metavar="DIR", help="learned planner's weights (see afford plan)"
    )
    br.add_argument(
        "--workers",
        type=int,
        default=min(2, os.cpu_count() or 1),
        help="parallel processes, one task each (default: 2, or 1 on a single core)",
    )
    br.add_argument(
        "--time-limit",
        type=float,
        default=60.0,
        metavar="SECONDS",
        help="tree search per task and planner stops growing after this long and plans from what it has "
        "(default 60; the oracle's trees at depth 3-4 can otherwise take minutes)",
    )
    br.add_argument("--out", metavar="FILE.json", help="also write the summary and every task's row here")
    br.add_argument("--json", action="store_true")
    _add_search_arguments(br, max_nodes=False)
    br.set_defaults(func=cmd_bench_random)

    dg = sub.add_parser(
        "diagnose",
        help="why the learned planner fails a task (recognition, prediction, goal or execution)",
        description="Plan each task with the learned planner and the oracle; where the learned plan fails, "
        "replay the oracle's plan through the learned nets and name the cause: execution (a recognised "
        "affordance was not there), recognition (the oracle's action is not among the edges recognised on "
        "the predicted state), goal (the chosen plan truly matches the goal image as well, eq. 5) or "
        "prediction (the net foresaw the oracle plan's effects wrongly). Oracle trees of 4 steps take "
        "minutes.",
    )
    dg.add_argument("tasks", nargs="+", metavar="TASK.json|DIR", help="task files, or folders of them")
    dg.add_argument(
        "--weights", "--run-dir", metavar="DIR", help="learned planner's weights (see afford plan)"
    )
    dg.add_argument("--json", action="store_true")
    dg.set_defaults(func=cmd_diagnose)

    from afford.cli import data, nets

    data.add_parsers(sub)
    nets.add_parsers(sub)
    return p


def main(argv: list[str] | None = None) -> int:
    from afford.data.format import DataError
    from afford.planning.tasks import TaskError
    from afford.planning.tree import TreeTooLarge
    from afford.planning.uncertain import EnsembleError
    from afford.sim.perturb import PerturbError
    from afford.sim.scene import SceneError
    from afford.training.checkpoint import CheckpointError
    from afford.training.memory import keep_freed_memory

    args = build_parser().parse_args(argv)
    keep_freed_memory()  # the nets' large tensors recur every step: keep their memory
    try:
        return args.func(args)
    except (
        CLIError,
        SceneError,
        TaskError,
        DataError,
        CheckpointError,
        TreeTooLarge,
        EnsembleError,
        PerturbError,
    ) as e:
        print(f"afford: error: {e}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("afford: interrupted", file=sys.stderr)  # one line, not a traceback
        return 130


if __name__ == "__main__":
    sys.exit(main())
