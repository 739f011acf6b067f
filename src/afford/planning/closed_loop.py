"""Plan, act, look again: closed-loop planning (beyond paper IV.C).

The paper plans once and executes the whole plan without looking. Here the planner plans from
what the camera sees, the first action of its plan is executed in the world, the real image is
taken, and it plans again from that image with the steps left, towards the same goal. It stops
when the chosen plan is empty (no state in the tree is predicted closer to the goal than the
state as it is; farther, for a negative goal, eq. 4) or the task's step budget is spent. This
is model-predictive control on the paper's planner: an error of the world model at one step
(a blurred prediction, a side effect not foreseen) is seen and planned around at the next.

Each re-plan is recorded: the action taken, the state the plan predicted after it, the state
observed, and eq. (5) between the two (the whole image as the patch): how far the world
departed from the model's foresight.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from afford.planning.tree import SearchResult
from afford.sim.affordances import Affordance
from afford.sim.scene import Scene


@dataclass
class LoopStep:
    """One round of the loop: a plan made from the observed state, and its first action taken."""

    plan: tuple[Affordance, ...]  # the whole plan chosen this round
    predicted: np.ndarray  # (H, W, 4): the state the plan foresaw after its first action
    observed: np.ndarray  # (H, W, 4): the state the world showed after it
    gap: float  # eq. (5) between predicted and observed, over the whole image
    executed: bool  # the simulator could carry the action out
    nodes: int  # states the round's search grew
    seconds: float  # the round's planning time
    search: SearchResult  # the round's tree, for reports

    @property
    def action(self) -> Affordance:
        return self.plan[0]

    def to_dict(self) -> dict:
        return {
            "action": self.action.to_dict(),
            "plan": [a.to_dict() for a in self.plan],
            "gap": round(self.gap, 6),
            "executed": self.executed,
            "nodes": self.nodes,
            "planning_seconds": round(self.seconds, 2),
        }


@dataclass
class Loop:
    """A closed-loop run: its rounds, the start's image, and how it stopped."""

    start: np.ndarray
    steps: list[LoopStep]
    stopped: str  # "goal": the plan chosen was empty; "budget": no steps left
    last: SearchResult | None  # the final round's tree when it chose the empty plan

    @property
    def plan(self) -> tuple[Affordance, ...]:
        """The actions taken, in order."""
        return tuple(s.action for s in self.steps)

    @property
    def seconds(self) -> float:
        return sum(s.seconds for s in self.steps) + (self.last.seconds if self.last else 0.0)

    @property
    def nodes(self) -> int:
        return sum(s.nodes for s in self.steps) + (len(self.last.nodes) - 1 if self.last else 0)


def image_gap(predicted: np.ndarray, observed: np.ndarray) -> float:
    """Eq. (5) with the whole observed image as the patch: the mean squared RGBD difference."""
    return float(np.mean((np.asarray(predicted, np.float64) - np.asarray(observed, np.float64)) ** 2))


def closed_loop(scene: Scene, plan_from: Callable[[int], SearchResult], max_steps: int) -> Loop:
    """Run the loop in `scene` from the state it is in now.

    `plan_from(steps_left)` plans from the scene's current state (it may move the scene, as
    the oracle's search does: the state is put back before the action is executed) and
    returns its search result, whose path gives the predicted states.
    """
    start = scene.observe()
    steps: list[LoopStep] = []
    last = None
    while len(steps) < max_steps:
        here = scene.snapshot()
        began = time.perf_counter()
        result = plan_from(max_steps - len(steps))
        seconds = time.perf_counter() - began
        if not result.plan:
            last = result
            break
        scene.restore(here)
        executed = scene.execute(result.plan[0]).executed
        observed = scene.observe()
        predicted = result.path()[1].image
        steps.append(
            LoopStep(
                result.plan,
                predicted,
                observed,
                image_gap(predicted, observed),
                executed,
                len(result.nodes) - 1,
                seconds,
                result,
            )
        )
    return Loop(start, steps, "goal" if last is not None else "budget", last)
