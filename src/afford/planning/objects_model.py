"""The object world model as the planner's world model (`--planner objects`).

The paper's search, unchanged: recognise affordances on each state image (the recognition net,
paper II.B), predict each child, score the leaves with eq. (4) and (5) against the goal image.
Only the prediction differs from `learned.py`: the start image is perceived as objects once,
the dynamics move the objects (P^a over objects, the likeliest outcome carried on), and the
child's image is drawn from its parent's (`objects/world.step`, the step the evaluations'
rollout takes too), so landings stay sharp and every pixel nothing touched stays exactly the
start's.

`ObjectsBranchingModel` keeps every outcome the dynamics foresee instead of the likeliest (as
`branches.py` does for the EM*D net): each state is a few branches, each its own objects and
drawing with the probability of the outcomes that led to it (the head calibrated,
`objects/calibration.py`), and a plan scores its expected eq. (5) over them, plus `risk`
standard deviations.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from afford.objects.draw import Drawer
from afford.objects.dynamics import ObjectDynamics, ObjectOutcomes
from afford.objects.perception import PerceptionNet
from afford.objects.world import ObjectState, perceived, step
from afford.planning.branches import keep, risky_scores
from afford.planning.goal import Goal
from afford.planning.learned import recognise_nodes
from afford.planning.tree import Node, Recognised, Scores, WorldModel
from afford.recognition.infer import Recognizer
from afford.sim.affordance import encode_affordance
from afford.sim.affordances import Affordance

# Two outcomes this alike are one next state: the dynamics' own thresholds for an object that
# did not move (DynamicsConfig.moved, .turned_deg).
SAME_M = 0.002
SAME_DEG = 3.0


class ObjectsModel(WorldModel):
    def __init__(
        self,
        image: np.ndarray,
        recognizer: Recognizer,
        perception: PerceptionNet,
        dynamics: ObjectDynamics,
        drawer: Drawer | None = None,
        start: ObjectState | None = None,
    ):
        """`start`: the objects to start from (`objects/world.given`) instead of the ones
        perception sees in `image`."""
        self.image = np.asarray(image, dtype=np.float32)
        self.recognizer = recognizer
        self.perception = perception
        self.dynamics = dynamics
        self.drawer = drawer if drawer is not None else Drawer()
        self.start = start

    def root(self):
        if self.start is not None:
            return self.image, self.start
        return self.image, perceived(self.perception, self.drawer, self.image[None])[0]

    def recognise(self, nodes: list[Node]) -> list[Recognised]:
        return recognise_nodes(self.recognizer, nodes)

    def predict(self, parents: list[Node], actions: list[Affordance]):
        before = np.stack([p.state.poses for p in parents])
        held = np.array([p.state.held for p in parents])
        rows = np.stack([encode_affordance(a) for a in actions])
        poses, held_next = self.dynamics.outcomes(before, held, rows).likeliest()
        return [
            step(self.drawer, parent.image, parent.state, poses[k], int(held_next[k]))
            for k, parent in enumerate(parents)
        ]


@dataclass
class ObjectBranches:
    """A state's alternatives, likeliest first: their probabilities (n,), summing to 1, each
    one's objects, and their images (n, H, W, C)."""

    probability: np.ndarray
    branches: list[ObjectState]
    images: np.ndarray


class ObjectsBranchingModel(ObjectsModel):
    """The object world model with every outcome of the dynamics kept as a branch; outcomes
    that put every object in the same place (`_alike`) are one branch, their probabilities
    summed, drawn from the likeliest of them. Recognition runs on the likeliest branch's
    image, which is also the state's picture."""

    def __init__(
        self,
        image: np.ndarray,
        recognizer: Recognizer,
        perception: PerceptionNet,
        dynamics: ObjectDynamics,
        drawer: Drawer | None = None,
        risk: float = 0.0,
        start: ObjectState | None = None,
    ):
        super().__init__(image, recognizer, perception, dynamics, drawer, start)
        self.risk = risk

    def root(self):
        image, state = super().root()
        return image, ObjectBranches(np.ones(1), [state], image[None])

    def predict(self, parents: list[Node], actions: list[Affordance]):
        owner = [(k, b) for k, p in enumerate(parents) for b in range(len(p.state.branches))]
        before = np.stack([parents[k].state.branches[b].poses for k, b in owner])
        held = np.array([parents[k].state.branches[b].held for k, b in owner])
        rows = np.stack([encode_affordance(actions[k]) for k, _ in owner])
        outcomes = self.dynamics.outcomes(before, held, rows)
        children, start = [], 0
        for parent in parents:
            mine = range(start, start + len(parent.state.branches))
            start = mine.stop
            prior = parent.state.probability
            found = _distinct(outcomes, mine, prior)
            probability = np.array([f.probability for f in found])
            kept = keep(probability / probability.sum())
            drawn = [
                step(
                    self.drawer,
                    parent.state.images[found[i].row - mine.start],
                    parent.state.branches[found[i].row - mine.start],
                    outcomes.poses[found[i].row, found[i].outcome],
                    int(outcomes.held[found[i].row, found[i].outcome]),
                )
                for i in kept
            ]
            p = probability[kept] / probability[kept].sum()
            images = np.stack([image for image, _ in drawn])
            children.append((images[0], ObjectBranches(p, [state for _, state in drawn], images)))
        return children

    def score(self, goal: Goal, nodes: list[Node]) -> Scores:
        return risky_scores(goal, [n.state for n in nodes], self.risk)


@dataclass
class _Next:
    """One distinct next state of a parent: its probability (summed over the outcomes alike),
    and the row (the parent's branch) and outcome of the likeliest of them, which is drawn."""

    probability: float
    row: int
    outcome: int
    best: float


def _distinct(outcomes: ObjectOutcomes, rows: range, prior: np.ndarray) -> list[_Next]:
    """The distinct next states of the branches `rows` (whose probabilities are `prior`)."""
    found: list[_Next] = []
    for row in rows:
        for o in range(outcomes.probability.shape[1]):
            p = float(prior[row - rows.start] * outcomes.probability[row, o])
            twin = next((f for f in found if _alike(outcomes, f.row, f.outcome, row, o)), None)
            if twin is None:
                found.append(_Next(p, row, o, p))
                continue
            twin.probability += p
            if p > twin.best:
                twin.row, twin.outcome, twin.best = row, o, p
    return found


def _alike(outcomes: ObjectOutcomes, row: int, o: int, row2: int, o2: int) -> bool:
    """Whether two outcomes hold the same object and put every object in the same place: the
    same ones gone, centres within SAME_M, axes within SAME_DEG (two outcomes of a net are never
    equal to the bit, and drawing both would cost a render for what looks the same)."""
    a, b = outcomes.poses[row, o], outcomes.poses[row2, o2]
    gone_a, gone_b = np.isnan(a[:, 0]), np.isnan(b[:, 0])
    if outcomes.held[row, o] != outcomes.held[row2, o2] or np.any(gone_a != gone_b):
        return False
    here = ~gone_a
    near = np.linalg.norm(a[here, :3] - b[here, :3], axis=-1) <= SAME_M
    turned = np.abs(np.sum(a[here, 3:7] * b[here, 3:7], axis=-1)) >= np.cos(np.radians(SAME_DEG) / 2)
    return bool(np.all(near & turned))
