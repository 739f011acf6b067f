"""Guided search (beam, best-first) on a toy world model whose goal lies six steps deep."""

import pytest
from helpers import GOAL_CELL, StepWorld, bar

from afford.planning.goal import Goal
from afford.planning.strategies import search
from afford.planning.tree import SearchConfig


def config(strategy: str, **kw) -> SearchConfig:
    return SearchConfig(progress=False, strategy=strategy, budget=300, **kw)


@pytest.mark.parametrize("strategy", ["beam", "best-first"])
def test_guided_search_finds_a_deep_plan_that_breadth_first_misses_on_the_same_budget(strategy):
    goal = Goal(bar(GOAL_CELL))
    wide = search(StepWorld(), goal, 6, config("breadth"))
    assert wide.truncated and wide.nodes[wide.best].state != GOAL_CELL  # 5^6 states do not fit in 300
    guided = search(StepWorld(), goal, 6, config(strategy, beam_width=4))
    assert guided.nodes[guided.best].state == GOAL_CELL and guided.loss == 0.0
    assert len(guided.plan) == 6 and len(guided.nodes) - 1 <= 300


def test_beam_keeps_beam_width_states_a_depth_and_best_first_spends_its_budget():
    goal = Goal(bar(GOAL_CELL))
    r = search(StepWorld(), goal, 6, config("beam", beam_width=3))
    assert r.per_depth[0] == 1 and all(n <= 3 * 5 for n in r.per_depth[1:])
    b = search(StepWorld(), goal, 20, SearchConfig(progress=False, strategy="best-first", budget=50, pop=2))
    assert len(b.nodes) - 1 == 50


def test_a_negative_goal_steers_guided_search_away_from_the_patch():
    r = search(StepWorld(), Goal(bar(0), negative=True), 3, config("beam", beam_width=2))
    assert r.nodes[r.best].state == 6  # as far from the start picture as 3 steps go


def test_an_unknown_strategy_is_refused():
    with pytest.raises(ValueError, match="unknown search"):
        search(StepWorld(), Goal(bar(1)), 1, SearchConfig(progress=False, strategy="sideways"))
