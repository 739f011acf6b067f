"""Each planner's search from what the camera sees now: the world models the planners grow,
built from a bundle of nets (`shipped.Nets`) and the simulator (`run.py` names the planners,
runs and judges them).
"""

from __future__ import annotations

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
from afford.shipped import Nets
from afford.sim.scene import Scene

if TYPE_CHECKING:  # imported where used: the object nets load torch models
    from afford.planning.objects_model import ObjectsModel

# How the learned planners use a net that foresees several outcomes per step (PlannerConfig.outcomes):
# carry on the likeliest, or keep them all as branches and score the expected eq. (5).
OUTCOMES = ("likeliest", "expected")


def check_outcomes(config: PlannerConfig) -> None:
    if config.outcomes not in OUTCOMES:
        raise UserError(f"outcomes: one of {', '.join(OUTCOMES)}, not {config.outcomes!r}")


def learned_model(image: np.ndarray, nets: Nets, config: PlannerConfig) -> LearnedModel | BranchingModel:
    """The learned world model from a start image: its likeliest outcome carried on, or every
    outcome a branch scored by the expected eq. (5) with the planner's risk."""
    check_outcomes(config)
    if config.outcomes == "expected":
        return BranchingModel(image, nets.recognizer, nets.predictor, config.risk)
    return LearnedModel(image, nets.recognizer, nets.predictor)


def learned_search(task: Task, scene: Scene, config: PlannerConfig, nets: Nets, steps: int) -> SearchResult:
    """The learned planner's search from what the camera sees now."""
    model = learned_model(scene.observe(), nets, config)
    result = search(model, task.goal, steps, config.search)
    if config.optimise_turns:
        from afford.planning.angles import with_optimised_turns

        result = with_optimised_turns(result, model, task.goal)
    return result


def oracle_search(task: Task, scene: Scene, config: PlannerConfig, nets: Nets, steps: int) -> SearchResult:
    return search(OracleModel(scene), task.goal, steps, config.search)


def perceived_sim_search(
    task: Task, scene: Scene, config: PlannerConfig, nets: Nets, steps: int
) -> SearchResult:
    """The oracle's search over a simulator scene built from the objects perceived in what the
    camera sees now (objects/simulated.py): what planning loses to perception alone."""
    from afford.planning.perceived_sim import PerceivedSimModel

    model = PerceivedSimModel(scene.observe(), nets.perception, nets.simulator)
    return search(model, task.goal, steps, config.search)


def objects_model(image: np.ndarray, config: PlannerConfig, nets: Nets, start=None) -> ObjectsModel:
    """The object world model on `image`: its likeliest outcome carried on, or every outcome a
    branch (PlannerConfig.outcomes); from the perceived objects, or from `start` (`objects/world.given`)."""
    from afford.planning.objects_model import ObjectsBranchingModel, ObjectsModel

    parts = (image, nets.recognizer, nets.perception, nets.dynamics, nets.drawer)
    if config.outcomes == "expected":
        return ObjectsBranchingModel(*parts, risk=config.risk, start=start)
    return ObjectsModel(*parts, start=start)


def objects_search(
    task: Task, scene: Scene, config: PlannerConfig, nets: Nets, steps: int, start=None
) -> SearchResult:
    """The paper's search with the object world model: objects perceived (or `start`), moved
    and drawn."""
    model = objects_model(scene.observe(), config, nets, start)
    result = search(model, task.goal, steps, config.search)
    if config.optimise_turns:  # the angle is the dynamics' input: searched, not descended
        from afford.planning.angles import with_searched_turns

        result = with_searched_turns(result, model, task.goal)
    return result


def true_objects_search(
    task: Task, scene: Scene, config: PlannerConfig, nets: Nets, steps: int
) -> SearchResult:
    """The object world model's search from the simulator's objects as they are now, not the
    perceived ones (`--planner objects-true`: beside `objects`, what perception costs a plan)."""
    from afford.data.draws import pose_array
    from afford.objects.world import given

    held = [name for name, _ in scene.slots].index(scene.held) if scene.held else -1
    start = given(nets.drawer, pose_array(scene), held, scene.instance_mask())
    return objects_search(task, scene, config, nets, steps, start)
