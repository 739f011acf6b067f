"""`afford plan`, `afford bench tasks|random` and `afford diagnose`: planning a task, many tasks,
and why a learned plan failed."""

from __future__ import annotations

import json
import os
import sys
from pathlib import Path

from afford.cli.errors import CLIError
from afford.cli.options import (
    add_perturb_arguments,
    add_search_arguments,
    add_time_limit_argument,
    add_weights_argument,
    check_closed_loop,
    load_needs,
    nets_of,
    output_folder,
    planner_config,
    planners_help,
)
from afford.cli.options import perturbation as perturbation_of
from afford.cli.options import planners as planner_names
from afford.cli.words import goal_reading, reading_line


def _outcome_line(o) -> str:
    plan = "-" if o.plan is None else " > ".join(a.type + (f"{a.turn:+g}" if a.turn else "") for a in o.plan)
    return f"{'solved' if o.success else 'FAILED'}: {plan}"


def cmd_plan(args) -> int:
    """Plan a task file, execute the plan in the simulator, draw it (paper Fig. 8)."""
    from afford.planning.run import execute_perturbed, solve
    from afford.planning.tasks import load_task, sentence_task
    from afford.sim.scene import Scene
    from afford.viz.plan import plan_strip
    from afford.words.facts import State

    check_closed_loop(args, (args.planner,))
    reading = None  # how a --goal sentence was read
    scene = Scene()
    nets = nets_of(args)
    if args.scene is not None:
        if not args.goal:
            raise CLIError("--scene needs --goal SENTENCE")
        task = sentence_task(args.scene, args.goal, args.steps, scene, nets)
        reading = goal_reading(args.goal, task.goal.statement, State.of_scene(scene))
        if not args.json:
            print(reading_line(reading), flush=True)
    else:
        if args.goal:
            raise CLIError("--goal goes with --scene; a task file holds its own goal")
        task = load_task(args.task, scene, nets)
    out = output_folder(args.out)
    perturbation = perturbation_of(args)
    load_needs(nets, (args.planner,))
    config = planner_config(args, progress=not args.json)
    outcome = solve(task, args.planner, scene, config, nets)
    if perturbation is not None:
        execute_perturbed(outcome, task, scene, perturbation, args.executions, config=config, nets=nets)
    picture = out / f"{task.name}-{args.planner}.png"
    plan_strip(outcome, task.goal, picture)
    record = outcome.to_dict() | {"picture": str(picture)} | ({"goal_read": reading} if reading else {})
    if args.report:
        from afford.viz.report import write_report

        record["report"] = str(write_report(outcome, task.goal, args.report))
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
        if args.report:
            print(f"  report: {args.report}")
    scene.close()
    return 0 if outcome.success else 1


def cmd_bench_tasks(args) -> int:
    """Every task of a folder with one planner: a table (paper IV.C, Fig. 8)."""
    from afford.planning.run import execute_perturbed, solve
    from afford.planning.tasks import load_task
    from afford.sim.scene import Scene
    from afford.viz.plan import plan_strip

    folders = [f.strip() for f in args.tasks.split(",") if f.strip()]
    files = []
    for folder in folders:
        found = sorted(Path(folder).glob("*.json"))
        if not found:
            raise CLIError(f"{folder}: no task files (*.json) there")
        files += [(folder, f) for f in found]
    planners = planner_names(args.planner)
    check_closed_loop(args, planners)
    perturbation = perturbation_of(args)
    nets = nets_of(args, planners)
    config = planner_config(args, progress=False)
    scene = Scene()
    report = {}
    for planner in planners:
        rows = []
        for folder, f in files:
            task = load_task(f, scene, nets)
            live = not args.json and sys.stdout.isatty()
            if live:
                print(f"{task.name} ...", end="", flush=True)
            o = solve(task, planner, scene, config, nets)
            if perturbation is not None:
                execute_perturbed(o, task, scene, perturbation, args.executions, config=config, nets=nets)
            if args.out:
                plan_strip(o, task.goal, Path(args.out) / f"{task.name}-{planner}.png")
            rows.append(o.to_dict() | {"folder": folder})
            if not args.json:
                back = "\r" if live else ""
                print(f"{back}{task.name:32s} {_outcome_line(o)}  [{o.nodes} nodes, {o.seconds:.1f} s]")
                if o.reason:
                    print(f"{'':32s} {o.reason}")
                if o.perturbed:
                    print(f"{'':32s} perturbed: {sum(o.perturbed)}/{len(o.perturbed)} executions succeed")
        solved = sum(r["solved"] for r in rows)
        report[planner] = {"solved": solved, "tasks": rows}
        if len(folders) > 1:  # each set beside the others: the paper's tasks, variants of them
            report[planner]["folders"] = {
                d: {
                    "solved": sum(r["solved"] for r in rows if r["folder"] == d),
                    "tasks": sum(r["folder"] == d for r in rows),
                }
                for d in folders
            }
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
            for d, c in report[planner].get("folders", {}).items():
                print(f"  {d}: {c['solved']}/{c['tasks']}")
    if args.json:
        print(json.dumps(report, indent=2))
    scene.close()
    return 0


def cmd_bench_random(args) -> int:
    """Random goals (random scenes, 1 to --max-steps random executions), every planner: success
    rates with 95% intervals, the tasks planned over parallel workers."""
    from tqdm import tqdm

    from afford.planning.random_bench import BenchSpec, run, summarise

    if args.n < 1:
        raise CLIError("--n must be at least 1")
    if args.workers < 1:
        raise CLIError("--workers must be at least 1")
    if args.time_limit is not None and args.time_limit <= 0:
        raise CLIError("--time-limit must be positive (seconds)")
    if not 1 <= args.min_steps <= args.max_steps:
        raise CLIError("--min-steps must be at least 1 and at most --max-steps")
    planners = planner_names(args.planner)
    check_closed_loop(args, planners)
    nets = nets_of(args, planners)  # a folder that lacks a net is one line here, not a worker's traceback
    threads = max(1, (os.cpu_count() or 1) // args.workers)
    spec = BenchSpec(
        max_steps=args.max_steps,
        planners=planners,
        weights=args.weights,
        prediction=None if nets.prediction_file is None else str(nets.prediction_file),
        time_limit=args.time_limit,
        threads=threads,
        min_steps=args.min_steps,
        planner=planner_config(args, progress=False),
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
            "closed_loop": args.closed_loop,
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
    from afford.planning.outcome import PlannerConfig
    from afford.planning.tasks import load_task
    from afford.planning.tree import SearchConfig
    from afford.sim.scene import Scene

    files = []
    for given in args.tasks:
        path = Path(given)
        found = sorted(path.glob("*.json")) if path.is_dir() else [path]
        if not found:
            raise CLIError(f"{given}: no task files (*.json) there")
        files += found
    nets = nets_of(args, (args.planner,))
    config = PlannerConfig(search=SearchConfig(progress=False))
    scene = Scene()
    out = []
    for f in tqdm(files, desc="diagnose", unit="task", disable=args.json or len(files) == 1):
        task = load_task(f, scene, nets)
        d = diagnose(task, scene, nets, config, args.planner)
        out.append(d.to_dict())
        if not args.json:
            tqdm.write(d.describe())
    if args.json:
        print(json.dumps(out, indent=2))
    scene.close()
    return 0


def add_parsers(sub) -> None:
    from afford.planning.diagnose import PLANNERS as DIAGNOSABLE
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
        "checked by the simulator), perceived-sim (the simulator run on the objects perception sees), "
        "objects (the object world model: objects perceived, moved by learned dynamics and drawn), "
        "hybrid-objects (canonical plans checked by the object world model), objects-true (the object "
        "world model started from the simulator's true objects: beside objects, what perception costs). "
        "Writes a picture like the paper's Fig. 8 and a JSON record. Exit status 1 when the executed plan "
        "misses the goal.",
    )
    given = pl.add_mutually_exclusive_group(required=True)
    given.add_argument("--task", metavar="TASK.json")
    given.add_argument(
        "--scene",
        metavar="SCENE.json",
        help="a scene file ({'objects': [...]}, as `afford scene --save` writes), planned to --goal",
    )
    pl.add_argument(
        "--goal",
        metavar="SENTENCE",
        help='with --scene: the goal in words (paper V), e.g. "the cup is on the block and the ball is '
        'gone"; success is the sentence judged on the true poses after the plan',
    )
    pl.add_argument(
        "--steps", type=int, default=4, help="with --scene: the most actions a plan may take (default 4)"
    )
    pl.add_argument(
        "--planner", choices=PLANNERS, default="oracle", help=f"one of {', '.join(PLANNERS)} (default oracle)"
    )
    pl.add_argument("--out", default="out/plan", metavar="DIR", help="where the picture and record go")
    pl.add_argument("--json", action="store_true", help="print the record as JSON")
    pl.add_argument(
        "--report",
        metavar="FILE.html",
        help="also write one self-contained HTML page of the search tree (paper Fig. 5): every state's "
        "image with the affordances recognised on it and its eq. (5) loss, the chosen path marked; "
        "closed loop: one tree per round",
    )
    add_perturb_arguments(pl)
    add_weights_argument(pl, detail=True)
    add_time_limit_argument(pl)
    add_search_arguments(pl)
    pl.set_defaults(func=cmd_plan)

    b = sub.add_parser("bench", help="benchmarks", description="Benchmarks over a set of tasks.")
    bsub = b.add_subparsers(dest="bench", required=True)
    bt = bsub.add_parser(
        "tasks",
        help="plan and execute every task of a folder, print a table",
        description="Plan every task file in a folder with one planner, execute each plan, and print "
        "solved / plan / plan length / nodes / planning seconds per task.",
    )
    bt.add_argument("--planner", default="oracle", metavar="NAME[,NAME]|all", help=planners_help())
    add_weights_argument(bt)
    bt.add_argument(
        "--tasks",
        default="tasks/paper",
        metavar="DIR[,DIR]",
        help="folder of task files, or several as a comma list, each counted apart (e.g. "
        "tasks/paper,tasks/variants: the paper's tasks beside variants of them; default tasks/paper)",
    )
    bt.add_argument("--out", metavar="DIR", help="also write each plan's picture here")
    bt.add_argument("--json", action="store_true")
    add_perturb_arguments(bt)
    add_time_limit_argument(bt)
    add_search_arguments(bt)
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
    br.add_argument("--planner", default="all", metavar="NAME[,NAME]|all", help=planners_help())
    add_weights_argument(br)
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
    add_search_arguments(br, max_nodes=False)
    br.set_defaults(func=cmd_bench_random)

    dg = sub.add_parser(
        "diagnose",
        help="why the learned planner fails a task (recognition, prediction, goal or execution)",
        description="Plan each task with the learned planner (or, with --planner objects, the object world "
        "model) and the oracle; where the learned plan fails, replay the oracle's plan through its world "
        "model and name the cause: execution (a recognised "
        "affordance was not there), recognition (the oracle's action is not among the edges recognised on "
        "the predicted state), goal (the chosen plan truly matches the goal image as well, eq. 5) or "
        "prediction (the net foresaw the oracle plan's effects wrongly). Oracle trees of 4 steps take "
        "minutes.",
    )
    dg.add_argument("tasks", nargs="+", metavar="TASK.json|DIR", help="task files, or folders of them")
    dg.add_argument(
        "--planner",
        choices=DIAGNOSABLE,
        default="learned",
        help="whose world model the oracle's plan is replayed through: the EM*D nets' (learned, the "
        "default) or the object world model's (objects)",
    )
    add_weights_argument(dg)
    dg.add_argument("--json", action="store_true")
    dg.set_defaults(func=cmd_diagnose)
