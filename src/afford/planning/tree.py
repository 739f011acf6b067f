"""Tree search over affordances (paper II.D, Fig. 5).

From the current state, recognition gives the edges (affordances) out of a node; execution
parameters are filled in (each turn becomes +90 and -90); of symmetric affordances that differ
only in gripper angle the most confident is kept; prediction gives each child state; every
state is scored against the goal image, eq. (5). The search is breadth-first to `max_steps`
and batched per depth level; the plan is the node of least loss (positive goal) or greatest
loss (negative goal), eq. (4).

The search knows the world only through a `WorldModel`: the simulator (the oracle) and the
learned EM*D pathway both implement it, so the same search runs on either.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import Any, Protocol

import numpy as np
from tqdm import tqdm

from afford.planning.goal import Goal
from afford.sim.affordances import Affordance, parametrise
from afford.sim.constants import TOLERANCES


@dataclass
class Node:
    """A state in the tree: the plan that leads to it from the root and what it looks like.

    state: whatever the world model needs to continue from here (a simulator snapshot, or a
    latent and memory trace).
    """

    plan: tuple[Affordance, ...]
    image: np.ndarray  # (H, W, 4) RGBD
    state: Any
    parent: int = -1
    loss: float = float("nan")

    @property
    def depth(self) -> int:
        return len(self.plan)


Recognised = list[tuple[Affordance, float]]  # affordances with their confidence


class WorldModel(Protocol):
    """What the search needs of a model of the world."""

    def root(self) -> tuple[np.ndarray, Any]:
        """The current state: its image and the model's state for it."""

    def recognise(self, nodes: list[Node]) -> list[Recognised]:
        """The affordances (with confidences) on each node's state."""

    def predict(self, parents: list[Node], actions: list[Affordance]) -> list[tuple[np.ndarray, Any] | None]:
        """Each parent's child after its action: (image, state), or None where the action
        cannot be carried out at all."""


@dataclass(frozen=True)
class SearchConfig:
    """How the tree is grown and the plan chosen."""

    batch_size: int = 256  # states recognised / predicted per batch (the authors used 256)
    merge_radius: float = TOLERANCES.merge_radius  # metres: symmetric affordances this close are one
    # Plans whose loss is within this of the best count as equally good: the shortest wins.
    tie_tolerance: float = 1e-4
    progress: bool = True
    # Seconds after which the tree stops growing (checked between batches); the plan is then
    # chosen among the states grown so far. None: no limit.
    time_limit: float | None = None
    # The most states a tree may hold: a depth expected to pass it is refused before it is
    # grown (TreeTooLarge says by how much). The paper's tasks need at most ~700. None: no limit.
    max_nodes: int | None = 20_000


class TreeTooLarge(ValueError):
    """A depth of the tree would pass `SearchConfig.max_nodes`; the message gives the estimate."""


@dataclass
class SearchResult:
    nodes: list[Node]
    best: int
    seconds: float
    expanded: int  # nodes whose affordances were recognised
    per_depth: list[int] = field(default_factory=list)  # nodes at each depth
    truncated: bool = False  # the time limit stopped the tree before max_steps

    @property
    def plan(self) -> tuple[Affordance, ...]:
        return self.nodes[self.best].plan

    @property
    def loss(self) -> float:
        return self.nodes[self.best].loss

    def path(self, index: int | None = None) -> list[Node]:
        """The nodes from the root to `index` (default: the chosen plan's end)."""
        i = self.best if index is None else index
        out = []
        while i >= 0:
            out.append(self.nodes[i])
            i = self.nodes[i].parent
        return out[::-1]


def edges(recognised: Recognised, merge_radius: float) -> list[Affordance]:
    """The edges out of a node: one of each group of symmetric duplicates (the most
    confident), then execution parameters filled in (paper II.D)."""
    kept: list[tuple[Affordance, float]] = []
    for aff, conf in sorted(recognised, key=lambda ac: -ac[1]):
        if aff.symmetric and any(
            k.symmetric
            and k.type == aff.type
            and np.linalg.norm(np.subtract(k.position, aff.position)) <= merge_radius
            for k, _ in kept
        ):
            continue
        kept.append((aff, conf))
    return parametrise([a for a, _ in kept])


def search(
    model: WorldModel, goal: Goal, max_steps: int, config: SearchConfig = SearchConfig()
) -> SearchResult:
    """Grow the tree breadth-first to `max_steps` and pick the plan for `goal`."""
    start = time.perf_counter()
    image, state = model.root()
    nodes = [Node((), image, state)]
    nodes[0].loss = float(goal.loss(image[None])[0])
    frontier = [0]
    expanded = 0
    per_depth = [1]
    bs = config.batch_size
    truncated = False

    def out_of_time() -> bool:
        return config.time_limit is not None and time.perf_counter() - start > config.time_limit

    for depth in range(max_steps):
        if config.max_nodes is not None and depth > 0:
            # Before recognising: the last level's branching factor, carried one level on.
            branching = per_depth[-1] / max(per_depth[-2], 1)
            _refuse(depth, len(nodes), len(frontier) * branching, config.max_nodes, "about ")
        children: list[tuple[int, Affordance]] = []
        bar = tqdm(
            total=len(frontier),
            desc=f"depth {depth + 1}/{max_steps}: recognise",
            disable=not config.progress,
            leave=False,
        )
        for b in range(0, len(frontier), bs):
            if out_of_time():
                truncated = True
                break
            batch = frontier[b : b + bs]
            for i, rec in zip(batch, model.recognise([nodes[i] for i in batch]), strict=True):
                children.extend((i, a) for a in edges(rec, config.merge_radius))
            expanded += len(batch)
            bar.update(len(batch))
        bar.close()
        if config.max_nodes is not None:
            _refuse(depth, len(nodes), len(children), config.max_nodes, "")  # now exact
        frontier = []
        bar = tqdm(
            total=len(children), desc=f"depth {depth + 1}/{max_steps}: predict", disable=not config.progress
        )
        for b in range(0, len(children), bs):
            if out_of_time():
                truncated = True
                break
            batch = children[b : b + bs]
            made = model.predict([nodes[i] for i, _ in batch], [a for _, a in batch])
            new = [
                Node(nodes[i].plan + (a,), out[0], out[1], parent=i)
                for (i, a), out in zip(batch, made, strict=True)
                if out is not None
            ]
            if new:
                losses = goal.loss(np.stack([n.image for n in new]))
                for n, loss in zip(new, losses, strict=True):
                    n.loss = float(loss)
                    frontier.append(len(nodes))
                    nodes.append(n)
            bar.update(len(batch))
        bar.close()
        per_depth.append(len(frontier))
        if not frontier or truncated:
            break
    best = choose(nodes, goal, config.tie_tolerance)
    return SearchResult(nodes, best, time.perf_counter() - start, expanded, per_depth, truncated)


def _refuse(depth: int, have: int, adds: float, limit: int, about: str) -> None:
    if have + adds > limit:
        raise TreeTooLarge(
            f"depth {depth + 1} would add {about}{adds:,.0f} states to the {have:,} grown (limit {limit:,}): "
            "plan fewer steps, or raise the limit (--max-nodes)"
        )


def choose(nodes: list[Node], goal: Goal, tie_tolerance: float) -> int:
    """Eq. (4) over every node; among near-equal losses the shortest plan."""
    losses = np.array([n.loss for n in nodes])
    best = losses[goal.best(losses)]
    good = np.abs(losses - best) <= tie_tolerance
    candidates = np.flatnonzero(good)
    return int(min(candidates, key=lambda i: (nodes[i].depth, -losses[i] if goal.negative else losses[i])))
