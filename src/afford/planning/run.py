"""Plan a task with a named planner, execute the plan in the simulator, judge it.

This is what `afford plan` and `afford bench tasks` run: one `Outcome` per task, with the
planned states (for pictures), the executed ones, and why a failure failed.
"""

from __future__ import annotations

from functools import cache, partial
from typing import TYPE_CHECKING

import numpy as np

from afford.errors import UserError
from afford.planning.branches import BranchingModel
from afford.planning.closed_loop import Loop, closed_loop
from afford.planning.hybrid import PROPOSALS, plan_hybrid
from afford.planning.judge import execute_plan
from afford.planning.learned import LearnedModel
from afford.planning.oracle import OracleModel
from afford.planning.outcome import Outcome, PlannerConfig
from afford.planning.strategies import search
from afford.planning.symbolic import plan_symbolic
from afford.planning.symbolic_outcome import solve_symbolic
from afford.planning.tasks import Task
from afford.planning.tree import SearchResult
from afford.planning.uncertain import EnsembleBranchingModel, EnsembleModel
from afford.sim.affordances import Affordance
from afford.sim.perturb import Perturbation, piles, reset_perturbed
from afford.sim.scene import Scene

if TYPE_CHECKING:  # imported where used: the object nets load torch models
    from afford.planning.objects_model import ObjectsModel

# How the learned planners use a net that foresees several outcomes per step (PlannerConfig.outcomes):
# carry on the likeliest, or keep them all as branches and score the expected eq. (5).
# (image, learned nets, config) -> the world model; "expected" takes the planner's risk.
OUTCOME_MODELS = {
    "likeliest": lambda image, nets, config: LearnedModel(image, nets.recognizer, nets.predictor),
    "expected": lambda image, nets, config: BranchingModel(
        image, nets.recognizer, nets.predictor, config.risk
    ),
}

# The same for the ensemble planner: each member carries on its likeliest outcome, or keeps
# every outcome as a branch. (image, learned nets, config) -> the world model.
ENSEMBLE_MODELS = {
    "likeliest": lambda image, nets, config: EnsembleModel(image, nets.recognizer, nets.members, config.risk),
    "expected": lambda image, nets, config: EnsembleBranchingModel(
        image, nets.recognizer, nets.members, config.risk
    ),
}


def solve(
    task: Task, planner: str, scene: Scene, config: PlannerConfig | None = None, learned=None
) -> Outcome:
    """Plan `task` with `planner`; `learned`: the `LearnedNets` for the planners that use them
    (None: the shipped ones)."""
    if planner not in PLANNER_REGISTRY:
        raise ValueError(f"unknown planner {planner!r}; expected one of {PLANNERS}")
    config = config or PlannerConfig()
    if config.closed_loop:
        return _solve_closed_loop(task, planner, scene, config, learned)
    return PLANNER_REGISTRY[planner](task, scene, config, learned)


def _oracle(task: Task, scene: Scene, config: PlannerConfig, learned) -> Outcome:
    scene.reset(task.scene)
    return _judge(task, "oracle", _oracle_search(task, scene, config, None, task.max_steps), scene)


def _nets(learned):
    """The `LearnedNets` given, or the weights shipped in the package."""
    if learned is None:
        from afford.shipped import load_learned

        return load_learned()
    return learned


def _learned_model(image: np.ndarray, learned, config: PlannerConfig) -> LearnedModel:
    """The learned world model from a start image, keeping the outcomes as `config` asks."""
    return _outcome_model(OUTCOME_MODELS, image, learned, config)


def _outcome_model(models: dict, image: np.ndarray, learned, config: PlannerConfig):
    if config.outcomes not in models:
        raise UserError(f"outcomes: one of {', '.join(models)}, not {config.outcomes!r}")
    return models[config.outcomes](image, learned, config)


def _learned(task: Task, scene: Scene, config: PlannerConfig, learned) -> Outcome:
    scene.reset(task.scene)
    result = _learned_search(task, scene, config, _nets(learned), task.max_steps)
    return _judge(task, "learned", result, scene)


def _learned_search(task: Task, scene: Scene, config: PlannerConfig, learned, steps: int) -> SearchResult:
    """The learned planner's search from what the camera sees now."""
    model = _learned_model(scene.observe(), learned, config)
    result = search(model, task.goal, steps, config.search)
    if config.optimise_turns:
        from afford.planning.angles import with_optimised_turns

        result = with_optimised_turns(result, model, task.goal)
    return result


def _ensemble_search(task: Task, scene: Scene, config: PlannerConfig, learned, steps: int) -> SearchResult:
    model = _outcome_model(ENSEMBLE_MODELS, scene.observe(), learned, config)
    return search(model, task.goal, steps, config.search)


def _oracle_search(task: Task, scene: Scene, config: PlannerConfig, learned, steps: int) -> SearchResult:
    return search(OracleModel(scene), task.goal, steps, config.search)


_SIMULATOR: list[Scene] = []  # the second simulator the perceived-sim planner builds its states in


def _perceived_sim_search(
    task: Task, scene: Scene, config: PlannerConfig, learned, steps: int
) -> SearchResult:
    """The oracle's search over a simulator scene built from the objects perceived in what the
    camera sees now (objects/simulated.py): what planning loses to perception alone."""
    from afford.planning.perceived_sim import PerceivedSimModel
    from afford.shipped import load_object_perception

    if not _SIMULATOR:
        _SIMULATOR.append(Scene())
    perception = load_object_perception(config.objects_weights, fallback=True)
    model = PerceivedSimModel(scene.observe(), perception, _SIMULATOR[0])
    return search(model, task.goal, steps, config.search)


_DRAWER: list = []  # the simulator the objects planner draws its states with


@cache
def _object_nets(folder: str | None) -> tuple:
    """The object perception and dynamics nets of a weights folder, each the shipped one where
    the folder lacks it; loaded once, since a closed loop builds its world model every round."""
    from afford.shipped import load_object_dynamics, load_object_perception

    return load_object_perception(folder, fallback=True), load_object_dynamics(folder, fallback=True)


def _objects_model(image: np.ndarray, config: PlannerConfig, learned, start=None) -> ObjectsModel:
    """The object world model on `image`: its likeliest outcome carried on, or every outcome a
    branch (PlannerConfig.outcomes); from the perceived objects, or from `start` (TrueStart)."""
    from afford.objects.draw import Drawer
    from afford.planning.objects_model import ObjectsBranchingModel, ObjectsModel

    if not _DRAWER:
        _DRAWER.append(Drawer())
    perception, dynamics = _object_nets(config.objects_weights)
    parts = (image, _nets(learned).recognizer, perception, dynamics, _DRAWER[0])
    if config.outcomes == "expected":
        return ObjectsBranchingModel(*parts, risk=config.risk, start=start)
    return ObjectsModel(*parts, start=start)


def _objects_search(
    task: Task, scene: Scene, config: PlannerConfig, learned, steps: int, start=None
) -> SearchResult:
    """The paper's search with the object world model: objects perceived (or `start`), moved
    and drawn."""
    model = _objects_model(scene.observe(), config, learned, start)
    result = search(model, task.goal, steps, config.search)
    if config.optimise_turns:  # the angle is the dynamics' input: searched, not descended
        from afford.planning.angles import with_searched_turns

        result = with_searched_turns(result, model, task.goal)
    return result


def _objects(task: Task, scene: Scene, config: PlannerConfig, learned) -> Outcome:
    scene.reset(task.scene)
    return _judge(task, "objects", _objects_search(task, scene, config, learned, task.max_steps), scene)


def _objects_true(task: Task, scene: Scene, config: PlannerConfig, learned) -> Outcome:
    """The object world model's search started from the true objects, not the perceived ones."""
    from afford.data.draws import pose_array
    from afford.planning.objects_model import TrueStart

    scene.reset(task.scene)  # a task starts with the gripper empty
    start = TrueStart(pose_array(scene), -1, scene.instance_mask())
    return _judge(
        task, "objects-true", _objects_search(task, scene, config, learned, task.max_steps, start), scene
    )


def _perceived_sim(task: Task, scene: Scene, config: PlannerConfig, learned) -> Outcome:
    scene.reset(task.scene)
    return _judge(
        task, "perceived-sim", _perceived_sim_search(task, scene, config, None, task.max_steps), scene
    )


def _ensemble(task: Task, scene: Scene, config: PlannerConfig, learned) -> Outcome:
    scene.reset(task.scene)
    result = _ensemble_search(task, scene, config, _nets(learned), task.max_steps)
    outcome = _judge(task, "ensemble", result, scene)
    outcome.spread = result.nodes[result.best].spread
    return outcome


def execute_perturbed(
    outcome: Outcome,
    task: Task,
    scene: Scene,
    perturbation: Perturbation,
    executions: int,
    seed: int = 0,
    config: PlannerConfig | None = None,
    learned=None,
) -> list[bool]:
    """`perturbed_successes` of the outcome's plan, recorded on the outcome, and returned.
    Planners plan on the task's start; the world then differs. With `config.closed_loop` the
    outcome's planner instead runs its loop from each perturbed start, seeing the world as it
    is after every step."""
    if config is not None and config.closed_loop:
        base = piles(scene, task.scene)
        nets = _nets(learned) if outcome.planner in USES_NETS else None
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


def _symbolic(task: Task, scene: Scene, config: PlannerConfig, learned) -> Outcome:
    return solve_symbolic(task, scene)


def _hybrid(task: Task, scene: Scene, config: PlannerConfig, learned) -> Outcome:
    return _solve_hybrid(task, "hybrid", scene, config, _nets(learned))


def _hybrid_oracle(task: Task, scene: Scene, config: PlannerConfig, learned) -> Outcome:
    return _solve_hybrid(task, "hybrid-oracle", scene, config, None)


def _hybrid_objects(task: Task, scene: Scene, config: PlannerConfig, learned) -> Outcome:
    return _solve_hybrid(task, "hybrid-objects", scene, config, _nets(learned))


# The world models a plan can be checked or replayed with (hybrid planners, `diagnose.py`):
# (scene, image seen, config, learned nets) -> WorldModel.
WORLD_MODELS = {
    "learned": lambda scene, image, config, learned: _learned_model(image, learned, config),
    "oracle": lambda scene, image, config, learned: OracleModel(scene),
    "objects": lambda scene, image, config, learned: _objects_model(image, config, learned),
}
# Each hybrid planner's world model, which checks the canonical plans.
HYBRID_MODELS = {"hybrid": "learned", "hybrid-oracle": "oracle", "hybrid-objects": "objects"}


class ClosedLoopError(UserError):
    """A planner that cannot re-plan from what it sees."""


def _solve_closed_loop(task: Task, planner: str, scene: Scene, config: PlannerConfig, learned) -> Outcome:
    """Plan, execute the first action, observe, plan again (planning/closed_loop.py)."""
    if planner not in CLOSED_LOOP:
        raise ClosedLoopError(
            f"the {planner} planner has no world model to plan again from what it sees; "
            f"closed loop takes {', '.join(CLOSED_LOOP)}"
        )
    learned = _nets(learned) if planner in USES_NETS else None
    loop, success = _closed_loop_run(task, planner, scene, config, learned, lambda: scene.reset(task.scene))
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
    task: Task, planner: str, scene: Scene, config: PlannerConfig, learned, start
) -> tuple[Loop, bool]:
    """One loop from the state `start()` puts the scene in: the loop, and whether the task's
    check holds after it."""
    plan_from = CLOSED_LOOP[planner](task, scene, config, learned)
    start()
    loop = closed_loop(scene, plan_from, task.max_steps)
    return loop, bool(task.success.holds(scene))


def _searcher(plan):
    """A closed-loop round for a planner that searches a tree: `plan(task, scene, config,
    learned, steps_left)` from the scene's current state."""

    def make(task: Task, scene: Scene, config: PlannerConfig, learned):
        return lambda steps: plan(task, scene, config, learned, steps)

    return make


def _hybrid_rounds(planner: str):
    """Closed-loop hybrid: the canonical proposals are made once, from the task's start; each
    round the planner's world model checks, from the observed state, the rest of every
    proposal that began with the actions taken so far, and searches when it keeps none."""
    make_model = WORLD_MODELS[HYBRID_MODELS[planner]]

    def rounds(task: Task, scene: Scene, config: PlannerConfig, learned):
        proposals = plan_symbolic(
            scene, task.scene, task.object_names(), task.success, task.max_steps, samples=PROPOSALS
        ).plans
        taken: list[Affordance] = []

        def plan_from(steps: int) -> SearchResult:
            model = make_model(scene, scene.observe(), config, learned)
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


def _solve_hybrid(task: Task, name: str, scene: Scene, config: PlannerConfig, learned) -> Outcome:
    """Canonical proposals checked by the planner's world model (HYBRID_MODELS), built on the
    scene reset to the task's start; search as the fallback (`hybrid.py`)."""
    proposals = plan_symbolic(
        scene, task.scene, task.object_names(), task.success, task.max_steps, samples=PROPOSALS
    )
    scene.reset(task.scene)
    model = WORLD_MODELS[HYBRID_MODELS[name]](scene, scene.observe(), config, learned)
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


# Each planner: (task, scene, search config, learned nets or None) -> Outcome.
PLANNER_REGISTRY = {
    "oracle": _oracle,
    "symbolic": _symbolic,
    "learned": _learned,
    "hybrid": _hybrid,  # canonical proposals checked by the learned nets (paper V)
    "hybrid-oracle": _hybrid_oracle,  # the same, checked by the simulator
    "ensemble": _ensemble,  # the learned planner on an ensemble of prediction nets, risk-averse (paper V)
    "perceived-sim": _perceived_sim,  # the simulator run from perceived objects (objects/simulated.py)
    "objects": _objects,  # the object world model: objects perceived, moved by learned dynamics, drawn
    "hybrid-objects": _hybrid_objects,  # canonical proposals checked by the object world model
    "objects-true": _objects_true,  # the object world model from the true objects: what perception costs
}
PLANNERS = tuple(PLANNER_REGISTRY)
# Each planner that can plan again from an observed state: (task, scene, config, learned nets
# or None) -> plan_from(steps left) -> SearchResult, for `closed_loop`.
CLOSED_LOOP = {
    "oracle": _searcher(_oracle_search),
    "learned": _searcher(_learned_search),
    "hybrid": _hybrid_rounds("hybrid"),
    "hybrid-oracle": _hybrid_rounds("hybrid-oracle"),
    "ensemble": _searcher(_ensemble_search),
    "perceived-sim": _searcher(_perceived_sim_search),
    "objects": _searcher(_objects_search),
    "hybrid-objects": _hybrid_rounds("hybrid-objects"),
}
# The planners that load the trained nets.
USES_NETS = ("learned", "hybrid", "ensemble", "objects", "hybrid-objects", "objects-true")
