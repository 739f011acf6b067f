"""Hybrid planning: canonical proposals checked by a world model, the search as the fallback."""

from pathlib import Path

import pytest
from helpers import GOAL_CELL, StepWorld, bar

from afford.planning.goal import Goal
from afford.planning.hybrid import kept, plan_hybrid
from afford.planning.run import PlannerConfig
from afford.planning.tree import SearchConfig
from afford.sim.affordances import Affordance

QUIET = SearchConfig(progress=False, strategy="beam", beam_width=4, budget=300)


def moves(*cells: int) -> tuple[Affordance, ...]:
    return tuple(Affordance("grasp", (float(c), 0.0, 0.0), 0.0, False) for c in cells)


def test_a_proposal_the_model_predicts_to_reach_the_goal_is_the_plan_and_nothing_is_searched():
    world = StepWorld()
    right, short = moves(2, 4, 6, 8, 10, 12), moves(2, 4)
    r = plan_hybrid(world, Goal(bar(GOAL_CELL)), [short, right], 6, QUIET)
    assert r.source == "symbolic" and r.plan == right and r.rejected == 1
    assert len(r.search.nodes) == 1 + 6  # the shared prefix (2, 4) predicted once


def test_when_every_proposal_is_rejected_the_search_runs():
    # One misses the goal; the other has a step the model cannot carry out (off the line).
    wrong, impossible = moves(1, 0), moves(-1, 1)
    r = plan_hybrid(StepWorld(), Goal(bar(GOAL_CELL)), [wrong, impossible], 6, QUIET)
    assert r.source == "fallback" and r.rejected == 2
    assert r.search.nodes[r.search.best].state == GOAL_CELL  # the beam search found it


def test_no_proposal_at_all_falls_back_too():
    r = plan_hybrid(StepWorld(), Goal(bar(4)), [], 2, QUIET)
    assert r.source == "fallback" and r.search.nodes[r.search.best].state == 4


def test_keeping_needs_a_proposal_to_close_half_the_distance():
    positive, negative = Goal(bar(1)), Goal(bar(1), negative=True)
    assert kept(positive, 0.2, 0.1) and not kept(positive, 0.2, 0.11)
    assert kept(negative, 0.1, 0.2) and not kept(negative, 0.1, 0.19) and not kept(negative, 0.0, 0.0)


@pytest.mark.slow
def test_hybrid_oracle_plans_a_paper_task_from_a_checked_canonical_plan(scene):
    from afford.planning.run import solve
    from afford.planning.tasks import load_task

    task = load_task(Path(__file__).parents[1] / "tasks/paper/01-order.json", scene)
    o = solve(task, "hybrid-oracle", scene, PlannerConfig(search=SearchConfig(progress=False)))
    assert o.source == "symbolic" and o.success and len(o.plan) == 4


def test_the_accept_share_sets_how_close_a_kept_proposal_must_come():

    near = moves(2, 4, 6, 8, 10)  # 10 of the 12 cells: most of the way
    loose = plan_hybrid(StepWorld(), Goal(bar(GOAL_CELL)), [near], 6, QUIET, accept=0.5)
    strict = plan_hybrid(StepWorld(), Goal(bar(GOAL_CELL)), [near], 6, QUIET, accept=0.99)
    assert loose.source == "symbolic" and strict.source == "fallback"
