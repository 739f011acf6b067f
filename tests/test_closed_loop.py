"""Closed-loop planning (planning/closed_loop.py) in a toy world whose first step slips."""

from dataclasses import dataclass

import numpy as np
from helpers import bar

from afford.planning.closed_loop import closed_loop, image_gap
from afford.planning.goal import Goal
from afford.planning.strategies import search
from afford.planning.tree import SearchConfig, WorldModel
from afford.sim.affordance import Affordance, Detection

TARGET = 4  # two steps of +2 from cell 0
QUIET = SearchConfig(progress=False)


class Reach(WorldModel):
    """The model: from state p a grasp at q reaches q, for q within 2 of p."""

    def __init__(self, start: int):
        self.start = start

    def root(self):
        return bar(self.start), self.start

    def recognise(self, nodes):
        grasps = (range(n.state - 2, n.state + 3) for n in nodes)
        return [
            [Detection(Affordance("grasp", (float(q), 0.0, 0.0), 0.0, False)) for q in qs] for qs in grasps
        ]

    def predict(self, parents, actions):
        return [(bar(int(a.position[0])), int(a.position[0])) for a in actions]


@dataclass
class Done:
    executed: bool


class SlipWorld:
    """The world: as the model says, except that its first action falls one cell short, and
    an action more than 2 cells away cannot be carried out."""

    def __init__(self):
        self.p, self.actions = 0, 0

    def snapshot(self):
        return self.p

    def restore(self, p):
        self.p = p

    def observe(self):
        return bar(self.p)

    def execute(self, a):
        q = int(a.position[0])
        if abs(q - self.p) > 2:
            return Done(False)
        self.p = q - 1 if self.actions == 0 else q
        self.actions += 1
        return Done(True)


def plan_from(world, goal):
    return lambda steps: search(Reach(world.p), goal, steps, QUIET)


def test_closed_loop_recovers_from_a_step_that_departs_from_its_prediction():
    goal = Goal(bar(TARGET))
    open_world = SlipWorld()
    plan = search(Reach(0), goal, 5, QUIET).plan
    for a in plan:  # open loop: the whole plan, blind
        open_world.execute(a)
    assert len(plan) == 2 and open_world.p != TARGET

    world = SlipWorld()
    loop = closed_loop(world, plan_from(world, goal), max_steps=5)
    assert world.p == TARGET and loop.stopped == "goal"
    first = loop.steps[0]
    assert first.gap > 0 and image_gap(first.predicted, bar(2)) == 0  # foresaw 2, saw 1
    assert np.array_equal(first.observed, bar(1))
    assert all(s.gap == 0 for s in loop.steps[1:])  # after the slip the model is right
    assert loop.last is not None and loop.last.plan == ()


def test_the_loop_stops_when_the_step_budget_is_spent():
    goal = Goal(bar(TARGET))
    world = SlipWorld()
    loop = closed_loop(world, plan_from(world, goal), max_steps=2)
    assert len(loop.steps) == 2 and loop.stopped == "budget" and loop.last is None
    assert world.p != TARGET


def test_the_loop_takes_no_step_when_the_state_is_already_the_goal():
    world = SlipWorld()
    loop = closed_loop(world, plan_from(world, Goal(bar(0))), max_steps=3)
    assert loop.steps == [] and loop.stopped == "goal" and loop.plan == ()
