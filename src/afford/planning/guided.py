"""Guided tree search: expand the states that look closest to the goal first (paper V).

Breadth-first search (paper II.D) grows every branch, so its tree multiplies by the
branching factor (~10-30 here) per step and a 5-6 step plan is out of reach. Section V asks
for "heuristics to constrain which branches are expanded"; the heuristic here is the plan
loss itself, eq. (5) of each (predicted) state against the goal patch, ranked by eq. (4)'s
order (least loss first for a positive goal, greatest for a negative one). Both strategies
use the same batched recognise and predict steps as breadth-first search (`tree.Growth`),
so they run on any world model, and stop at `SearchConfig.budget` states grown
(`tree.GUIDED_BUDGET` by default):

- beam: per depth, the `beam_width` best states of the last depth are expanded;
- best-first: the `pop` best states not yet expanded, of any depth, are expanded together.

The plan is chosen as in breadth-first search: eq. (4) over every state grown.
"""

from __future__ import annotations

import heapq

from afford.planning.tree import Growth, SearchResult, breadth_first


def _order(tree: Growth, index: int) -> float:
    """Eq. (4)'s order as a number to sort by: smaller is closer to the goal."""
    loss = tree.nodes[index].loss
    return -loss if tree.goal.negative else loss


def beam(tree: Growth, max_steps: int) -> SearchResult:
    """Beam search: each depth's `beam_width` best states are expanded. The children of the
    better parents come first, so when the budget cuts a depth short it drops the worst."""
    frontier = [0]
    for depth in range(max_steps):
        if tree.room() <= 0:
            break
        children = tree.recognise(frontier, f"beam depth {depth + 1}/{max_steps}: recognise")
        made = tree.predict(children[: tree.room()], f"beam depth {depth + 1}/{max_steps}: predict")
        frontier = sorted(made, key=lambda i: _order(tree, i))[: tree.config.beam_width]
        if not frontier or tree.truncated:
            break
    return tree.result(tree.per_depth())


def best_first(tree: Growth, max_steps: int) -> SearchResult:
    """Best-first search: the `pop` best open states, of any depth, are expanded per round,
    until the budget is spent, the time limit passes or no state shallower than `max_steps`
    is left open."""
    from tqdm import tqdm

    open_nodes = [(_order(tree, 0), 0)]
    quiet = not tree.config.progress
    with tqdm(total=tree.room(), desc="best-first", unit="state", disable=quiet) as bar:
        while open_nodes and tree.room() > 0 and not tree.truncated:
            batch = [heapq.heappop(open_nodes)[1] for _ in range(min(tree.config.pop, len(open_nodes)))]
            children = tree.recognise(batch, None)
            made = tree.predict(children[: tree.room()], None)
            for i in made:
                if tree.nodes[i].depth < max_steps:
                    heapq.heappush(open_nodes, (_order(tree, i), i))
            bar.update(len(made))
    return tree.result(tree.per_depth())


# Each strategy: (a tree holding only its root, max steps) -> SearchResult.
STRATEGIES = {"breadth": breadth_first, "beam": beam, "best-first": best_first}
