"""How a tree is grown: breadth-first (paper II.D), or guided to the goal (paper V).

Breadth-first search grows every node of a depth before the next depth: every branch, so
its tree multiplies by the branching factor (~10-30 here) per step and a 5-6 step plan is
out of reach. Section V asks for "heuristics to constrain which branches are expanded"; the
heuristic of the guided strategies is the plan loss itself, eq. (5) of each (predicted)
state against the goal patch, ranked by eq. (4)'s order (least loss first for a positive
goal, greatest for a negative one). All strategies use the same batched recognise and
predict steps (`tree.Growth`), so they run on any world model; the guided ones stop at
`SearchConfig.budget` states grown (`tree.GUIDED_BUDGET` by default):

- breadth: every node of a depth, then the next depth (the paper's);
- beam: per depth, the `beam_width` best states of the last depth are expanded;
- best-first: the `pop` best states not yet expanded, of any depth, are expanded together.

Every strategy chooses the plan alike: eq. (4) over every state grown (`tree.choose`).
"""

from __future__ import annotations

import heapq
import time

from tqdm import tqdm

from afford.planning.goal import Goal
from afford.planning.tree import Growth, SearchConfig, SearchResult, TreeTooLarge, WorldModel


def breadth_first(tree: Growth, max_steps: int) -> SearchResult:
    """The paper's search: every node of a depth expanded before the next depth."""
    config = tree.config
    frontier, per_depth = [0], [1]
    for depth in range(max_steps):
        if config.max_nodes is not None and depth > 0:
            # Before recognising: the last level's branching factor, carried one level on.
            branching = per_depth[-1] / max(per_depth[-2], 1)
            _refuse(depth, len(tree.nodes), len(frontier) * branching, config.max_nodes, "about ")
        children = tree.recognise(frontier, f"depth {depth + 1}/{max_steps}: recognise")
        if config.max_nodes is not None:
            _refuse(depth, len(tree.nodes), len(children), config.max_nodes, "")  # now exact
        if config.budget is not None and len(children) > tree.room():
            children, tree.truncated = children[: tree.room()], True
        frontier = tree.predict(children, f"depth {depth + 1}/{max_steps}: predict")
        per_depth.append(len(frontier))
        if not frontier or tree.truncated:
            break
        if config.max_nodes is not None and config.time_limit is None:  # a time limit bounds it already
            _refuse_whole(tree, per_depth, max_steps, config.max_nodes)
    return tree.result(per_depth)


# The whole-tree estimate is an extrapolation: it refuses only trees it puts past this many
# times the limit, and the exact check before each depth catches the rest.
ESTIMATE_MARGIN = 2.0


def whole_tree(per_depth: list[int], max_steps: int) -> tuple[float, float]:
    """(states, branching): the size of the whole tree of `max_steps`, extrapolated from the
    depths grown (root first) by the last depth's branching factor."""
    branching = per_depth[-1] / max(per_depth[-2], 1)
    rest = sum(per_depth[-1] * branching**j for j in range(1, max_steps - len(per_depth) + 2))
    return sum(per_depth) + rest, branching


def _refuse_whole(tree: Growth, per_depth: list[int], max_steps: int, limit: int) -> None:
    """From depth 2 on, refuse at once a tree whose deeper levels would pass the limit, so a
    task of too many steps is told so in seconds, not after growing depth after depth."""
    grown = len(per_depth) - 1
    if grown < 2 or grown >= max_steps:
        return
    total, branching = whole_tree(per_depth, max_steps)
    if total > ESTIMATE_MARGIN * limit:
        seconds = time.perf_counter() - tree.start
        raise TreeTooLarge(
            f"a tree of {max_steps} steps would hold about {total:,.0f} states (each state at depth {grown} "
            f"led to {branching:.1f}; {sum(per_depth):,} grown in {seconds:.0f} s), well past the limit of "
            f"{limit:,}: plan fewer steps, search with --search beam or best-first, or raise --max-nodes"
        )


def _refuse(depth: int, have: int, adds: float, limit: int, about: str) -> None:
    if have + adds > limit:
        raise TreeTooLarge(
            f"depth {depth + 1} would add {about}{adds:,.0f} states to the {have:,} grown (limit {limit:,}): "
            "plan fewer steps, or raise the limit (--max-nodes)"
        )


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


def search(model: WorldModel, goal: Goal, max_steps: int, config: SearchConfig | None = None) -> SearchResult:
    """Grow a tree to at most `max_steps` by `config.strategy` and pick the plan for `goal`."""
    config = SearchConfig() if config is None else config
    if config.strategy not in STRATEGIES:
        raise ValueError(f"unknown search {config.strategy!r}; expected one of {', '.join(STRATEGIES)}")
    return STRATEGIES[config.strategy](Growth(model, goal, config), max_steps)
