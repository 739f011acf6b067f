"""Plan a task with a named planner, execute the plan in the simulator, judge it.

This is what `afford plan` and `afford bench tasks` run: one `Outcome` per task, with the
planned states (for pictures), the executed ones, and why a failure failed.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from functools import partial

import numpy as np

from afford.errors import UserError
from afford.planning.closed_loop import Loop, closed_loop
from afford.planning.hybrid import PROPOSALS, plan_hybrid
from afford.planning.judge import execute_plan
from afford.planning.oracle import OracleModel
from afford.planning.outcome import Outcome, PlannerConfig
from afford.planning.searches import (
    learned_model,
    learned_search,
    objects_model,
    objects_search,
    oracle_search,
    perceived_sim_search,
    true_objects_search,
)
from afford.planning.symbolic import plan_symbolic
from afford.planning.symbolic_outcome import solve_symbolic
from afford.planning.tasks import Task
from afford.planning.tree import SearchResult, WorldModel
from afford.shipped import Nets
from afford.sim.affordances import Affordance
from afford.sim.perturb import Perturbation, piles, reset_perturbed
from afford.sim.scene import Scene


def solve(
    task: Task, planner: str, scene: Scene, config: PlannerConfig | None = None, nets: Nets | None = None
) -> Outcome:
    """Plan `task` with `planner` and the nets of `nets` it needs (None: the package's)."""
    if planner not in PLANNER_REGISTRY:
        raise ValueError(f"unknown planner {planner!r}; expected one of {PLANNERS}")
    config = config or PlannerConfig()
    nets = nets or Nets()
    if config.closed_loop:
        return _solve_closed_loop(task, planner, scene, config, nets)
    return PLANNER_REGISTRY[planner].solve(task, scene, config, nets)


def execute_perturbed(
    outcome: Outcome,
    task: Task,
    scene: Scene,
    perturbation: Perturbation,
    executions: int,
    seed: int = 0,
    config: PlannerConfig | None = None,
    nets: Nets | None = None,
) -> list[bool]:
    """`perturbed_successes` of the outcome's plan, recorded on the outcome, and returned.
    Planners plan on the task's start; the world then differs. With `config.closed_loop` the
    outcome's planner instead runs its loop from each perturbed start, seeing the world as it
    is after every step."""
    if config is not None and config.closed_loop:
        base = piles(scene, task.scene)
        nets = nets or Nets()
        outcome.perturbed = []
        for k in range(executions):
            draw = np.random.default_rng([seed, k])  # the same draws as the open-loop executions
            start = partial(reset_perturbed, scene, task.scene, perturbation, draw, base)
            outcome.perturbed.append(_closed_loop_run(task, outcome.planner, scene, config, nets, start)[1])
        return outcome.perturbed
    outcome.perturbed = perturbed_successes(outcome.plan or (), task, scene, perturbation, executions, seed)
    return outcome.perturbed


def perturbed_successes(
    plan, task: Task, scene: Scene, perturbation: Perturbation, executions: int, seed: int = 0
) -> list[bool]:
    """`plan` executed `executions` times, each from its own perturbed start (`sim/perturb.py`,
    draws seeded by `seed` and the execution's number): does the task's check hold after each?"""
    base = piles(scene, task.scene)  # read once: every draw perturbs the same start
    return [
        bool(
            execute_plan(
                scene, task.scene, plan, task.success, perturbation, np.random.default_rng([seed, k]), base
            ).success
        )
        for k in range(executions)
    ]


def _symbolic(task: Task, scene: Scene, config: PlannerConfig, nets: Nets) -> Outcome:
    return solve_symbolic(task, scene)


class ClosedLoopError(UserError):
    """A planner that cannot re-plan from what it sees."""


def _solve_closed_loop(task: Task, planner: str, scene: Scene, config: PlannerConfig, nets: Nets) -> Outcome:
    """Plan, execute the first action, observe, plan again (planning/closed_loop.py)."""
    if planner not in CLOSED_LOOP:
        raise ClosedLoopError(
            f"the {planner} planner has no world model to plan again from what it sees; "
            f"closed loop takes {', '.join(CLOSED_LOOP)}"
        )
    loop, success = _closed_loop_run(task, planner, scene, config, nets, lambda: scene.reset(task.scene))
    reason = "" if success else f"the success predicate ({task.success.describe()}) is false after the loop"
    last = loop.last.loss if loop.last is not None else (loop.steps[-1].search.loss if loop.steps else None)
    return Outcome(
        task=task.name,
        planner=planner,
        plan=loop.plan,
        planned=[loop.start] + [s.predicted for s in loop.steps],
        executed=[loop.start] + [s.observed for s in loop.steps],
        success=success,
        nodes=loop.nodes,
        seconds=loop.seconds,
        loss=last,
        reason=reason,
        steps_executed=[s.executed for s in loop.steps],
        truncated=any(s.search.truncated for s in loop.steps),
        loop=loop,
    )


def _closed_loop_run(
    task: Task, planner: str, scene: Scene, config: PlannerConfig, nets: Nets, start
) -> tuple[Loop, bool]:
    """One loop from the state `start()` puts the scene in: the loop, and whether the task's
    check holds after it."""
    plan_from = PLANNER_REGISTRY[planner].closed_loop(task, scene, config, nets)
    start()
    loop = closed_loop(scene, plan_from, task.max_steps)
    return loop, bool(task.success.holds(scene))


def _searcher(plan):
    """A closed-loop round for a planner that searches a tree: `plan(task, scene, config,
    nets, steps_left)` from the scene's current state."""

    def make(task: Task, scene: Scene, config: PlannerConfig, nets: Nets):
        return lambda steps: plan(task, scene, config, nets, steps)

    return make


def _hybrid_rounds(make_model: Callable):
    """Closed-loop hybrid: the canonical proposals are made once, from the task's start; each
    round the world model checks, from the observed state, the rest of every proposal that
    began with the actions taken so far, and searches when it keeps none."""

    def rounds(task: Task, scene: Scene, config: PlannerConfig, nets: Nets):
        proposals = plan_symbolic(
            scene, task.scene, task.object_names(), task.success, task.max_steps, samples=PROPOSALS
        ).plans
        taken: list[Affordance] = []

        def plan_from(steps: int) -> SearchResult:
            model = make_model(scene, scene.observe(), config, nets)
            rest = [
                p[len(taken) :]
                for p in proposals
                if tuple(p[: len(taken)]) == tuple(taken) and len(p) > len(taken)
            ]
            result = plan_hybrid(model, task.goal, rest, steps, config.search, config.accept).search
            if result.plan:
                taken.append(result.plan[0])
            return result

        return plan_from

    return rounds


def _solve_hybrid(
    task: Task, name: str, make_model: Callable, scene: Scene, config: PlannerConfig, nets: Nets
) -> Outcome:
    """Canonical proposals checked by a world model (`make_model`), built on the scene reset
    to the task's start; search as the fallback (`hybrid.py`)."""
    proposals = plan_symbolic(
        scene, task.scene, task.object_names(), task.success, task.max_steps, samples=PROPOSALS
    )
    scene.reset(task.scene)
    model = make_model(scene, scene.observe(), config, nets)
    hybrid = plan_hybrid(model, task.goal, proposals.plans, task.max_steps, config.search, config.accept)
    outcome = _judge(task, name, hybrid.search, scene, source=hybrid.source)
    outcome.seconds += proposals.seconds
    outcome.nodes += proposals.expanded
    if hybrid.source == "fallback" and hybrid.proposals:
        note = f"the world model rejected all {hybrid.proposals} canonical plans; searched instead"
        outcome.reason = "; ".join(r for r in (outcome.reason, note) if r)
    return outcome


def _judge(task: Task, name: str, result: SearchResult, scene: Scene, source: str = "") -> Outcome:
    """The planned plan executed open-loop in the simulator and judged by the task's predicate."""
    planned = [n.image for n in result.path()]
    ex = execute_plan(scene, task.scene, result.plan, task.success)
    reason = (
        "" if ex.success else f"the success predicate ({task.success.describe()}) is false after execution"
    )
    return Outcome(
        task=task.name,
        planner=name,
        plan=result.plan,
        planned=planned,
        executed=ex.images,
        success=ex.success,
        nodes=len(result.nodes) - 1,
        seconds=result.seconds,
        loss=result.loss,
        reason=reason,
        steps_executed=ex.executed,
        truncated=result.truncated,
        source=source,
        search=result,
    )


# A world model a plan can be checked or replayed with (hybrid planners, `diagnose.py`):
# (scene, image seen, config, nets) -> WorldModel.
WorldModelMaker = Callable[[Scene, np.ndarray, PlannerConfig, object], WorldModel]
# A planner's closed-loop round maker: (task, scene, config, nets) ->
# plan_from(steps left) -> SearchResult, planning from the scene as it is (`closed_loop`).
RoundMaker = Callable[[Task, Scene, PlannerConfig, object], Callable[[int], SearchResult]]


@dataclass(frozen=True)
class Planner:
    """One planner: how it plans and is judged (`solve`: (task, scene, config, nets) ->
    Outcome), the nets of the bundle it needs (`shipped.KINDS`: none for the simulator's and
    the canonical planners), how it plans again from an
    observed state (`closed_loop`; None: it cannot), and the world model it grows, for the
    hybrid planner built on it and `diagnose` (`world_model`; None: none to replay through)."""

    solve: Callable[[Task, Scene, PlannerConfig, object], Outcome]
    about: str
    needs: tuple[str, ...] = ()
    closed_loop: RoundMaker | None = None
    world_model: WorldModelMaker | None = None


def _searching(name: str, plan_search, needs: tuple[str, ...], about: str, world_model=None) -> Planner:
    """A planner that searches a tree from the task's start (`plan_search(task, scene, config,
    nets, steps)`), executed open loop and judged; in closed loop, the same search from
    each observed state."""

    def solve_it(task: Task, scene: Scene, config: PlannerConfig, nets: Nets) -> Outcome:
        scene.reset(task.scene)
        result = plan_search(task, scene, config, nets, task.max_steps)
        return _judge(task, name, result, scene)

    return Planner(solve_it, about, needs, _searcher(plan_search), world_model)


def _hybrid(name: str, base: Planner, about: str) -> Planner:
    """Canonical proposals checked by `base`'s world model (paper V), in closed loop too."""

    def solve_it(task: Task, scene: Scene, config: PlannerConfig, nets: Nets) -> Outcome:
        return _solve_hybrid(task, name, base.world_model, scene, config, nets)

    return Planner(solve_it, about, base.needs, _hybrid_rounds(base.world_model))


_LEARNED = _searching(
    "learned",
    learned_search,
    ("recognizer", "predictor"),
    "the paper's: affordances recognised in the EM*D net's predicted futures",
    lambda scene, image, config, nets: learned_model(image, nets, config),
)
_ORACLE = _searching(
    "oracle",
    oracle_search,
    (),
    "the paper's search with the simulator as its world model",
    lambda scene, image, config, nets: OracleModel(scene),
)
_OBJECTS = _searching(
    "objects",
    objects_search,
    ("recognizer", "perception", "dynamics"),
    "the object world model: objects perceived, moved by learned dynamics, drawn",
    lambda scene, image, config, nets: objects_model(image, config, nets),
)

# Every planner, one record each; `afford plan`, `afford bench` and the pictures take their
# names from here.
PLANNER_REGISTRY: dict[str, Planner] = {
    "oracle": _ORACLE,
    "symbolic": Planner(_symbolic, "canonical effects only: the baseline"),
    "learned": _LEARNED,
    "hybrid": _hybrid("hybrid", _LEARNED, "canonical proposals checked by the learned nets (paper V)"),
    "hybrid-oracle": _hybrid("hybrid-oracle", _ORACLE, "canonical proposals checked by the simulator"),
    "perceived-sim": _searching(
        "perceived-sim",
        perceived_sim_search,
        ("perception",),
        "the simulator run from the objects perception sees: what planning loses to perception alone",
    ),
    "objects": _OBJECTS,
    "hybrid-objects": _hybrid(
        "hybrid-objects", _OBJECTS, "canonical proposals checked by the object world model"
    ),
    "objects-true": _searching(
        "objects-true",
        true_objects_search,
        ("recognizer", "perception", "dynamics"),
        "the object world model from the true objects: what perception costs",
    ),
}
PLANNERS = tuple(PLANNER_REGISTRY)
# The planners that can plan again from an observed state (`--closed-loop`).
CLOSED_LOOP = tuple(name for name, p in PLANNER_REGISTRY.items() if p.closed_loop is not None)
# The planners that load trained nets.
USES_NETS = tuple(name for name, p in PLANNER_REGISTRY.items() if p.needs)
# The planners with a world model to replay a plan through (`diagnose`): those that learn it.
WORLD_MODELS = {name: p.world_model for name, p in PLANNER_REGISTRY.items() if p.world_model and p.needs}
