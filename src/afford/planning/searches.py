"""Each planner's search from what the camera sees now: the world models the planners grow,
built from the nets and the simulator (`run.py` names the planners, runs and judges them).
"""

from __future__ import annotations

from functools import cache
from typing import TYPE_CHECKING

import numpy as np

from afford.errors import UserError
from afford.planning.branches import BranchingModel
from afford.planning.learned import LearnedModel
from afford.planning.oracle import OracleModel
from afford.planning.outcome import PlannerConfig
from afford.planning.strategies import search
from afford.planning.tasks import Task
from afford.planning.tree import SearchResult
from afford.planning.uncertain import EnsembleBranchingModel, EnsembleModel
from afford.sim.scene import Scene

if TYPE_CHECKING:  # imported where used: the object nets load torch models
    from afford.planning.objects_model import ObjectsModel

# How the learned planners use a net that foresees several outcomes per step (PlannerConfig.outcomes):
# carry on the likeliest, or keep them all as branches and score the expected eq. (5).
OUTCOMES = ("likeliest", "expected")


def nets_or_shipped(learned):
    """The `LearnedNets` given, or the weights shipped in the package."""
    if learned is None:
        from afford.shipped import load_learned

        return load_learned()
    return learned


def check_outcomes(config: PlannerConfig) -> None:
    if config.outcomes not in OUTCOMES:
        raise UserError(f"outcomes: one of {', '.join(OUTCOMES)}, not {config.outcomes!r}")


def learned_model(image: np.ndarray, learned, config: PlannerConfig) -> LearnedModel | BranchingModel:
    """The learned world model from a start image: its likeliest outcome carried on, or every
    outcome a branch scored by the expected eq. (5) with the planner's risk."""
    check_outcomes(config)
    if config.outcomes == "expected":
        return BranchingModel(image, learned.recognizer, learned.predictor, config.risk)
    return LearnedModel(image, learned.recognizer, learned.predictor)


def learned_search(task: Task, scene: Scene, config: PlannerConfig, learned, steps: int) -> SearchResult:
    """The learned planner's search from what the camera sees now."""
    model = learned_model(scene.observe(), learned, config)
    result = search(model, task.goal, steps, config.search)
    if config.optimise_turns:
        from afford.planning.angles import with_optimised_turns

        result = with_optimised_turns(result, model, task.goal)
    return result


def ensemble_search(task: Task, scene: Scene, config: PlannerConfig, learned, steps: int) -> SearchResult:
    """The ensemble's search: each member carries on its likeliest outcome, or keeps every
    outcome as a branch."""
    check_outcomes(config)
    kind = EnsembleBranchingModel if config.outcomes == "expected" else EnsembleModel
    model = kind(scene.observe(), learned.recognizer, learned.members, config.risk)
    return search(model, task.goal, steps, config.search)


def oracle_search(task: Task, scene: Scene, config: PlannerConfig, learned, steps: int) -> SearchResult:
    return search(OracleModel(scene), task.goal, steps, config.search)


_SIMULATOR: list[Scene] = []  # the second simulator the perceived-sim planner builds its states in


def perceived_sim_search(
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


def objects_model(image: np.ndarray, config: PlannerConfig, learned, start=None) -> ObjectsModel:
    """The object world model on `image`: its likeliest outcome carried on, or every outcome a
    branch (PlannerConfig.outcomes); from the perceived objects, or from `start` (TrueStart)."""
    from afford.objects.draw import Drawer
    from afford.planning.objects_model import ObjectsBranchingModel, ObjectsModel

    if not _DRAWER:
        _DRAWER.append(Drawer())
    perception, dynamics = _object_nets(config.objects_weights)
    parts = (image, nets_or_shipped(learned).recognizer, perception, dynamics, _DRAWER[0])
    if config.outcomes == "expected":
        return ObjectsBranchingModel(*parts, risk=config.risk, start=start)
    return ObjectsModel(*parts, start=start)


def objects_search(
    task: Task, scene: Scene, config: PlannerConfig, learned, steps: int, start=None
) -> SearchResult:
    """The paper's search with the object world model: objects perceived (or `start`), moved
    and drawn."""
    model = objects_model(scene.observe(), config, learned, start)
    result = search(model, task.goal, steps, config.search)
    if config.optimise_turns:  # the angle is the dynamics' input: searched, not descended
        from afford.planning.angles import with_searched_turns

        result = with_searched_turns(result, model, task.goal)
    return result
