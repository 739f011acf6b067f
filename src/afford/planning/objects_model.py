"""The object world model as the planner's world model (`--planner objects`).

The paper's search, unchanged: recognise affordances on each state image (the recognition net,
paper II.B), predict each child, score the leaves with eq. (4) and (5) against the goal image.
Only the prediction differs from `learned.py`: the start image is perceived as objects once,
the dynamics move the objects (P^a over objects, the likeliest outcome carried on), and the
child's image is drawn from its parent's (`objects/draw.py`), so landings stay sharp and
every pixel nothing touched stays exactly the start's.

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
from afford.objects.dynamics import ObjectDynamics, predict
from afford.objects.perceive import perceive, slot_masks, to_state
from afford.objects.perception import PerceptionNet
from afford.objects.state import moved
from afford.planning.branches import keep, risky_scores
from afford.planning.goal import Goal
from afford.planning.learned import recognise_nodes
from afford.planning.tree import Node, Recognised, Scores, WorldModel
from afford.recognition.infer import Recognizer
from afford.sim.affordance import encode_affordance
from afford.sim.affordances import Affordance


@dataclass
class ObjectsState:
    """A node's objects: pose rows per slot (NaN: none), the held slot, the drawing of them
    that the child's drawing is compared with, and which slots' objects the image still
    shows as they were seen in the start image (not yet moved, so not yet redrawn)."""

    poses: np.ndarray
    held: int
    drawn: np.ndarray
    as_seen: np.ndarray


class ObjectsModel(WorldModel):
    def __init__(
        self,
        image: np.ndarray,
        recognizer: Recognizer,
        perception: PerceptionNet,
        dynamics: ObjectDynamics,
        drawer: Drawer | None = None,
    ):
        if dynamics.config.arm_path:
            raise ValueError("the planner's dynamics net must not need the arm's path: it is not known ahead")
        self.image = np.asarray(image, dtype=np.float32)
        self.recognizer = recognizer
        self.perception = perception
        self.dynamics = dynamics
        self.drawer = drawer if drawer is not None else Drawer()

    def root(self):
        objects = perceive(self.perception, self.image[None])[0]
        poses, held = to_state(objects)
        self.seen = slot_masks(objects)
        return self.image, ObjectsState(poses, held, self.drawer.render(poses, held), self.seen.any((1, 2)))

    def recognise(self, nodes: list[Node]) -> list[Recognised]:
        return recognise_nodes(self.recognizer, nodes)

    def predict(self, parents: list[Node], actions: list[Affordance]):
        before = np.stack([p.state.poses for p in parents])
        held = np.array([p.state.held for p in parents])
        rows = np.stack([encode_affordance(a) for a in actions])
        poses, held_next = predict(self.dynamics, before, held, rows).likeliest()
        return [
            self._child(parent.image, parent.state, poses[k], int(held_next[k]))
            for k, parent in enumerate(parents)
        ]

    def _child(self, image: np.ndarray, state: ObjectsState, poses: np.ndarray, held: int):
        """(image, state) of the objects moved to `poses`, drawn over `image` (eq. 3)."""
        drawn = self.drawer.render(poses, held)
        go = moved(state.poses, poses)
        seen = self.seen[go & state.as_seen].any(0)
        child = self.drawer.draw(image, state.drawn, drawn, seen)
        return child, ObjectsState(poses, held, drawn, state.as_seen & ~go)


@dataclass
class ObjectBranches:
    """A state's alternatives, likeliest first: their probabilities (n,), summing to 1, each
    one's objects, and their images (n, H, W, C)."""

    probability: np.ndarray
    branches: list[ObjectsState]
    images: np.ndarray


class ObjectsBranchingModel(ObjectsModel):
    """The object world model with every outcome of the dynamics kept as a branch; outcomes
    that put every object in the same place are one branch (their probabilities summed).
    Recognition runs on the likeliest branch's image, which is also the state's picture."""

    def __init__(self, *args, risk: float = 0.0, **kwargs):
        super().__init__(*args, **kwargs)
        self.risk = risk

    def root(self):
        image, state = super().root()
        return image, ObjectBranches(np.ones(1), [state], image[None])

    def predict(self, parents: list[Node], actions: list[Affordance]):
        owner = [(k, b) for k, p in enumerate(parents) for b in range(len(p.state.branches))]
        before = np.stack([parents[k].state.branches[b].poses for k, b in owner])
        held = np.array([parents[k].state.branches[b].held for k, b in owner])
        rows = np.stack([encode_affordance(actions[k]) for k, _ in owner])
        outcomes = predict(self.dynamics, before, held, rows)
        k_out = outcomes.probability.shape[1]
        children, start = [], 0
        for parent in parents:
            mine = range(start, start + len(parent.state.branches))
            start = mine.stop
            # (probability, row, outcome) of each distinct next state of this parent
            found: list[list] = []
            for row in mine:
                for o in range(k_out):
                    p = parent.state.probability[row - mine.start] * outcomes.probability[row, o]
                    twin = next((f for f in found if _same(outcomes, f[1], f[2], row, o)), None)
                    if twin is None:
                        found.append([p, row, o])
                    else:
                        twin[0] += p
            probability = np.array([f[0] for f in found])
            kept = keep(probability / probability.sum())
            drawn = [
                self._child(
                    parent.state.images[row - mine.start],
                    parent.state.branches[row - mine.start],
                    outcomes.poses[row, o],
                    int(outcomes.held[row, o]),
                )
                for _, row, o in (found[i] for i in kept)
            ]
            p = probability[kept] / probability[kept].sum()
            images = np.stack([image for image, _ in drawn])
            children.append((images[0], ObjectBranches(p, [state for _, state in drawn], images)))
        return children

    def score(self, goal: Goal, nodes: list[Node]) -> Scores:
        return risky_scores(goal, [n.state for n in nodes], self.risk)


def _same(outcomes, row: int, o: int, row2: int, o2: int) -> bool:
    """Whether two outcomes put every object in the same place and hold the same one."""
    return outcomes.held[row, o] == outcomes.held[row2, o2] and np.array_equal(
        outcomes.poses[row, o], outcomes.poses[row2, o2], equal_nan=True
    )
