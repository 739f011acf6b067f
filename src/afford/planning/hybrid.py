"""Hybrid planning (paper V): canonical plans proposed, a world model checks them, search falls back.

Section V: symbolic planning is cheap where canonical effects hold, so "a hybrid approach can
have significant advantages". The symbolic planner (`symbolic.py`) proposes its shortest
canonical plans; the world model (learned or oracle) predicts the outcome of each, sharing
common prefixes, and scores it against the goal patch, eq. (5). A proposal is kept when its
predicted outcome closes at least ACCEPT of the distance between the start and the goal
(for a negative goal: moves at least that much further from the patch); of the kept ones
the best by eq. (4) is the plan. Where none is kept (the canonical effects would fail, as
in tasks that need a non-canonical effect) or there is none, the tree search runs as usual.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

from afford.planning.goal import Goal
from afford.planning.strategies import search
from afford.planning.tree import Growth, SearchConfig, SearchResult, WorldModel
from afford.sim.affordances import Affordance

PROPOSALS = 32  # shortest canonical plans checked per task (drawn as the symbolic planner's sample)
ACCEPT = 0.5  # the share of the start's eq. (5) loss a proposal's outcome must remove


@dataclass
class HybridResult:
    search: SearchResult  # the checked proposals' tree (its best the plan), or the fallback's
    source: str  # "symbolic": a checked proposal; "fallback": the tree search
    proposals: int
    rejected: int

    @property
    def plan(self) -> tuple[Affordance, ...]:
        return self.search.plan


def kept(goal: Goal, start_loss: float, loss: float, accept: float = ACCEPT) -> bool:
    """Does a predicted outcome with `loss` reach far enough towards the goal?"""
    if goal.negative:
        return loss >= start_loss / (1 - accept) and loss > start_loss
    return loss <= (1 - accept) * start_loss


def check_proposals(
    model: WorldModel, goal: Goal, proposals: list[tuple[Affordance, ...]], config: SearchConfig
) -> tuple[Growth, list[int | None]]:
    """The world model's outcome of every proposal: a tree holding each plan's states (common
    prefixes predicted once) and, per proposal, its end node (None: a step cannot be carried
    out in the model)."""
    tree = Growth(model, goal, config)
    at: dict[tuple[Affordance, ...], int | None] = {(): 0}
    for depth in range(max((len(p) for p in proposals), default=0)):
        children: dict[tuple[Affordance, ...], tuple[int, Affordance]] = {}
        for p in proposals:
            parent = at.get(p[:depth])
            if len(p) > depth and parent is not None and p[: depth + 1] not in at:
                children[p[: depth + 1]] = (parent, p[depth])
        made = tree.predict(list(children.values()), None)
        for prefix in children:
            at[prefix] = None
        for i in made:
            at[tree.nodes[i].plan] = i
    return tree, [at.get(p) for p in proposals]


def plan_hybrid(
    model: WorldModel,
    goal: Goal,
    proposals: list[tuple[Affordance, ...]],
    max_steps: int,
    config: SearchConfig | None = None,
    accept: float = ACCEPT,
) -> HybridResult:
    """The best proposal the world model keeps (its predicted outcome removes at least `accept`
    of the start's loss), else the tree search (`config.strategy`)."""
    config = config or SearchConfig()
    start = time.perf_counter()
    tree, ends = check_proposals(model, goal, proposals, config)
    start_loss = tree.nodes[0].loss
    good = [i for i in ends if i is not None and kept(goal, start_loss, tree.nodes[i].loss, accept)]
    if good:
        losses = [tree.nodes[i].loss for i in good]
        best = good[goal.best(losses)]
        result = SearchResult(tree.nodes, best, time.perf_counter() - start, 0, tree.per_depth())
        return HybridResult(result, "symbolic", len(proposals), len(proposals) - len(good))
    fallback = search(model, goal, max_steps, config)
    fallback.seconds = time.perf_counter() - start  # the checks count too
    return HybridResult(fallback, "fallback", len(proposals), len(proposals))
