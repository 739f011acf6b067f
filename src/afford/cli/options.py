"""Options that several commands share: --weights, the planners, the search, perturbations."""

from __future__ import annotations

from afford.cli.errors import CLIError

MAX_NODES_HELP = (
    "refuse to grow a tree past this many states, with the estimate, before growing the depth that "
    "would pass it (default 20,000; 0: no limit; the paper's tasks need at most ~700)"
)


def add_weights_argument(parser, detail: bool = False) -> None:
    """--weights: the folder of every net the planners use (default: the package's)."""
    parser.add_argument(
        "--weights",
        "--run-dir",
        metavar="DIR",
        help="a weights folder in the package's layout (recognition.safetensors, prediction.safetensors, "
        "agreement.safetensors, objects/perception.safetensors and objects/dynamics.safetensors, "
        "as `afford weights export` writes them), or with recognition/ and prediction/ training runs; "
        "the planners load the nets they need from it (default: the weights shipped in the package)"
        if detail
        else "the planners' weights folder (see afford plan)",
    )


def output_folder(path):
    """The folder an --out names, made if missing; one line where it cannot be, checked before any
    work whose results it would hold."""
    from pathlib import Path

    out = Path(path)
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as e:
        raise CLIError(f"--out {path}: {e.strerror.lower()}") from None
    return out


def nets_of(args, planners: tuple[str, ...] = ()):
    """The bundle of nets a command plans or measures with (`shipped.Nets`): the --weights
    folder's (default: the package's), and with --optimise-turns alone the continuous-turn
    prediction net in place of the package's (paper V). The nets `planners` need are loaded
    here (`load_needs`)."""
    from afford.shipped import CONTINUOUS_PREDICTION, Nets

    weights = getattr(args, "weights", None)
    turns = weights is None and getattr(args, "optimise_turns", False)
    return load_needs(Nets(weights, CONTINUOUS_PREDICTION if turns else None), planners)


def load_needs(nets, planners: tuple[str, ...]):
    """The bundle with the nets `planners` need loaded: a folder that lacks one says so in one
    line before any planning."""
    from afford.planning.run import PLANNER_REGISTRY

    for name in planners:
        nets.check(PLANNER_REGISTRY[name].needs)
    return nets


def planners_help() -> str:
    """--planner's help for the commands that take several: the registry's names."""
    from afford.planning.run import PLANNERS

    return f"one planner ({', '.join(PLANNERS)}), several as a comma list, or all"


def planners(given: str) -> tuple[str, ...]:
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


def add_time_limit_argument(parser) -> None:
    """--time-limit for one plan's trees (`afford bench random` has its own, per task)."""
    parser.add_argument(
        "--time-limit",
        type=float,
        dest="plan_time_limit",
        metavar="SECONDS",
        help="each tree stops growing after this long and the plan is chosen from the states grown "
        "(default: no limit)",
    )


def check_closed_loop(args, names: tuple[str, ...]) -> None:
    """One line, before any planning, when --closed-loop meets a planner that cannot re-plan."""
    from afford.planning.run import CLOSED_LOOP

    cannot = [n for n in names if n not in CLOSED_LOOP]
    if getattr(args, "closed_loop", False) and cannot:
        raise CLIError(
            f"--closed-loop: the {cannot[0]} planner has no world model to plan again from what it sees; "
            f"closed loop takes {', '.join(CLOSED_LOOP)}"
        )


def add_search_arguments(parser, max_nodes: bool = True) -> None:
    """How the tree grows: the paper's breadth-first search, or a guided one (paper V)."""
    from afford.planning.run import PlannerConfig
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
        default=PlannerConfig.accept,
        metavar="SHARE",
        help="hybrid planners: a canonical plan is kept when its predicted outcome removes at least this "
        f"share of the start's goal loss, eq. 5 (default {PlannerConfig.accept})",
    )
    parser.add_argument(
        "--optimise-turns",
        action="store_true",
        help="learned planner: optimise the turn angles of the best plan with turns by gradient descent "
        "on eq. 5 through the prediction net (paper V), keeping it when it comes closer; needs a "
        "prediction net trained on continuous turns: without --weights, the one shipped for it "
        "(weights/continuous); objects planner: each turn's angle searched on a 5-degree grid "
        "instead, its dynamics taking the angle as an input",
    )
    parser.add_argument(
        "--risk",
        type=float,
        default=PlannerConfig.risk,
        metavar="W",
        help="learned, hybrid and objects planners with --outcomes expected: a plan scores its expected "
        "goal loss (eq. 5, over the branches of its foreseen outcomes) plus W standard deviations of it: "
        "risk-averse "
        f"(default {PlannerConfig.risk}); 0: the expected loss alone",
    )
    parser.add_argument(
        "--outcomes",
        choices=("likeliest", "expected"),
        default=PlannerConfig.outcomes,
        help="learned and hybrid planners, with a prediction net that foresees two outcomes per step (a "
        "canonical one and a side effect): likeliest, each step carries on the one its head finds "
        "likelier (default); expected, both are kept as branches and a plan scores its expected goal "
        "loss (eq. 5) over them; objects and hybrid-objects planners: the K "
        "outcomes of its dynamics "
        "the same way, with their calibrated probabilities",
    )
    parser.add_argument(
        "--closed-loop",
        action="store_true",
        help="plan, execute the first action, look at the real state, plan again with the steps left, "
        "until the plan chosen is empty or the steps are spent (every planner but symbolic); without it "
        "the whole plan is executed blind, as in the paper",
    )
    if max_nodes:
        parser.add_argument(
            "--max-nodes", type=int, default=SearchConfig.max_nodes, metavar="N", help=MAX_NODES_HELP
        )


def add_perturb_arguments(parser) -> None:
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


def perturbation(args):
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


def planner_config(args, progress: bool):
    """The planner's settings and its search's, from the command line."""
    from afford.planning.run import PlannerConfig
    from afford.planning.tree import SearchConfig

    if args.beam_width < 1:
        raise CLIError("--beam-width must be at least 1")
    if args.budget is not None and args.budget < 1:
        raise CLIError("--budget must be at least 1 state")
    if not 0 < args.accept < 1:
        raise CLIError("--accept must lie between 0 and 1")
    max_nodes = getattr(args, "max_nodes", SearchConfig.max_nodes)
    time_limit = getattr(args, "plan_time_limit", None)
    if time_limit is not None and time_limit <= 0:
        raise CLIError("--time-limit must be positive (seconds)")
    search = SearchConfig(
        progress=progress,
        time_limit=time_limit,
        max_nodes=max_nodes or None,
        strategy=args.search,
        beam_width=args.beam_width,
        budget=args.budget,
    )
    return PlannerConfig(
        search=search,
        accept=args.accept,
        optimise_turns=args.optimise_turns,
        risk=args.risk,
        closed_loop=args.closed_loop,
        outcomes=args.outcomes,
    )
