"""Tree search over affordances (paper II.D, Fig. 5).

From the current state, recognition gives the edges (affordances) out of a node; execution
parameters are filled in (each turn becomes +90 and -90); of symmetric affordances that differ
only in gripper angle the most confident is kept; prediction gives each child state; every
state is scored against the goal image, eq. (5). The search is breadth-first to `max_steps`
and batched per depth level; the plan is the node of least loss (positive goal) or greatest
loss (negative goal), eq. (4).

This module is the tree: its nodes, the two batched steps that grow it (`Growth`) and the
choice of plan (eq. 4). How it is grown, breadth-first (the paper's) or guided (section V's
"heuristics to constrain which branches are expanded"), is `strategies.py`, above it.

The search knows the world only through a `WorldModel`: the simulator (the oracle) and the
learned EM*D pathway both implement it, so the same search runs on either.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import Any, Protocol

import numpy as np
from tqdm import tqdm

from afford.errors import UserError
from afford.planning.goal import Goal
from afford.sim.affordance import Affordance, Detection
from afford.sim.affordances import parametrise
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
    # What recognition found on this state (None: not expanded), for reports of the tree.
    recognised: list[Detection] | None = None

    @property
    def depth(self) -> int:
        return len(self.plan)


Recognised = list[Detection]  # the affordances on one state, each with its confidence


@dataclass
class Scores:
    """Each node's plan score (eq. 5 against the goal, or a model's own), and for a model that
    keeps several outcomes per state (planning/branches.py) the standard deviation of eq. (5)
    over them, which the score counts by the planner's risk weight (None: one outcome)."""

    loss: np.ndarray
    spread: np.ndarray | None = None


class WorldModel(Protocol):
    """What the search needs of a model of the world. A model subclasses this and gives `root`,
    `recognise` and `predict`; `score` is eq. (5) on each node's image unless the model has its
    own (a model that keeps several outcomes scores their spread too)."""

    def root(self) -> tuple[np.ndarray, Any]:
        """The current state: its image and the model's state for it."""
        ...

    def recognise(self, nodes: list[Node]) -> list[Recognised]:
        """The affordances (with confidences) on each node's state."""
        ...

    def predict(self, parents: list[Node], actions: list[Affordance]) -> list[tuple[np.ndarray, Any] | None]:
        """Each parent's child after its action: (image, state), or None where the action
        cannot be carried out at all."""
        ...

    def score(self, goal: Goal, nodes: list[Node]) -> Scores:
        """Each node's plan score: eq. (5) of its image against the goal patch."""
        return Scores(goal.loss(np.stack([n.image for n in nodes])))


GUIDED_BUDGET = 2_000  # states a guided search grows unless told otherwise


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
    # How the tree grows (planning/strategies.py): "breadth" (the paper's), "beam" or "best-first".
    strategy: str = "breadth"
    beam_width: int = 16  # beam: the nodes of each depth kept for expansion
    # The most states grown: None gives the guided strategies GUIDED_BUDGET and breadth-first
    # no limit; set, it also cuts breadth-first short (to compare strategies on one budget).
    budget: int | None = None
    pop: int = 8  # best-first: the best open nodes expanded together (one batch for the nets)


class TreeTooLarge(UserError):
    """A depth of the tree would pass `SearchConfig.max_nodes`; the message gives the estimate."""


@dataclass
class SearchResult:
    nodes: list[Node]
    best: int
    seconds: float
    expanded: int  # nodes whose affordances were recognised
    per_depth: list[int] = field(default_factory=list)  # nodes at each depth
    truncated: bool = False  # the time limit (or breadth-first's budget) stopped the tree early

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
    confident), then execution parameters filled in (paper II.D).

    Recognition's own suppression (`recognition/targets.suppress`) already drops a detection
    near a more confident one of the same type within its 2.5 cm and 10 degrees; this merge is
    the planner's, and also applies to world models that do not go through the recognition net
    (the oracle's and the symbolic planner's ground truth lists a symmetric object at every
    quarter turn): symmetric affordances of one type within `merge_radius` are one action.
    """
    kept: list[Detection] = []
    for d in sorted(recognised, key=lambda d: -d.score):
        a = d.affordance
        if a.symmetric and any(
            k.affordance.symmetric
            and k.affordance.type == a.type
            and np.linalg.norm(np.subtract(k.affordance.position, a.position)) <= merge_radius
            for k in kept
        ):
            continue
        kept.append(d)
    return parametrise([d.affordance for d in kept])


class Growth:
    """A tree being grown: the nodes so far and the two batched steps every strategy uses."""

    def __init__(self, model: WorldModel, goal: Goal, config: SearchConfig):
        self.model, self.goal, self.config = model, goal, config
        self.start = time.perf_counter()
        image, state = model.root()
        self.nodes = [Node((), image, state)]
        self.scored(self.nodes)
        self.expanded = 0
        self.truncated = False  # the time limit stopped a step

    def scored(self, nodes: list[Node]) -> None:
        """Score new nodes against the goal (the model's `score`), on the nodes themselves."""
        scores = self.model.score(self.goal, nodes)
        for k, n in enumerate(nodes):
            n.loss = float(scores.loss[k])

    def room(self) -> int:
        """States the budget still allows (the root is not counted)."""
        budget = GUIDED_BUDGET if self.config.budget is None else self.config.budget
        return budget - (len(self.nodes) - 1)

    def out_of_time(self) -> bool:
        limit = self.config.time_limit
        return limit is not None and time.perf_counter() - self.start > limit

    def recognise(self, frontier: list[int], desc: str | None) -> list[tuple[int, Affordance]]:
        """The edges out of each node of `frontier`: (parent index, affordance). `desc`: the
        progress bar's label (None: no bar)."""
        children: list[tuple[int, Affordance]] = []
        bs = self.config.batch_size
        quiet = desc is None or not self.config.progress
        with tqdm(total=len(frontier), desc=desc, disable=quiet, leave=False) as bar:
            for b in range(0, len(frontier), bs):
                if self.out_of_time():
                    self.truncated = True
                    break
                batch = frontier[b : b + bs]
                for i, rec in zip(batch, self.model.recognise([self.nodes[i] for i in batch]), strict=True):
                    self.nodes[i].recognised = rec
                    children.extend((i, a) for a in edges(rec, self.config.merge_radius))
                self.expanded += len(batch)
                bar.update(len(batch))
        return children

    def predict(self, children: list[tuple[int, Affordance]], desc: str | None) -> list[int]:
        """Each child state predicted and scored by eq. (5); the indices of the new nodes."""
        made_here: list[int] = []
        bs, nodes = self.config.batch_size, self.nodes
        with tqdm(total=len(children), desc=desc, disable=desc is None or not self.config.progress) as bar:
            for b in range(0, len(children), bs):
                if self.out_of_time():
                    self.truncated = True
                    break
                batch = children[b : b + bs]
                made = self.model.predict([nodes[i] for i, _ in batch], [a for _, a in batch])
                new = [
                    Node(nodes[i].plan + (a,), out[0], out[1], parent=i)
                    for (i, a), out in zip(batch, made, strict=True)
                    if out is not None
                ]
                if new:
                    self.scored(new)
                    for n in new:
                        made_here.append(len(nodes))
                        nodes.append(n)
                bar.update(len(batch))
        return made_here

    def per_depth(self) -> list[int]:
        """States grown at each depth, the root's first."""
        depths = [n.depth for n in self.nodes]
        return [depths.count(d) for d in range(max(depths) + 1)]

    def result(self, per_depth: list[int]) -> SearchResult:
        best = choose(self.nodes, self.goal, self.config.tie_tolerance)
        seconds = time.perf_counter() - self.start
        return SearchResult(self.nodes, best, seconds, self.expanded, per_depth, self.truncated)


def choose(nodes: list[Node], goal: Goal, tie_tolerance: float) -> int:
    """Eq. (4) over every node; among near-equal losses the shortest plan."""
    losses = np.array([n.loss for n in nodes])
    best = losses[goal.best(losses)]
    good = np.abs(losses - best) <= tie_tolerance
    candidates = np.flatnonzero(good)
    return int(min(candidates, key=lambda i: (nodes[i].depth, -losses[i] if goal.negative else losses[i])))
