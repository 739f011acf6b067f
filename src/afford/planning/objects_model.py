"""The object world model as the planner's world model (`--planner objects`).

The paper's search, unchanged: recognise affordances on each state image (the recognition net,
paper II.B), predict each child, score the leaves with eq. (4) and (5) against the goal image.
Only the prediction differs from `learned.py`: the start image is perceived as objects once,
the dynamics move the objects (P^a over objects, the likeliest outcome carried on), and the
child's image is drawn from its parent's (`objects/draw.py`), so landings stay sharp and
every pixel nothing touched stays exactly the start's.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from afford.objects.draw import Drawer
from afford.objects.dynamics import ObjectDynamics, predict
from afford.objects.perceive import perceive, slot_masks, to_state
from afford.objects.perception import PerceptionNet
from afford.objects.state import moved
from afford.planning.learned import recognise_nodes
from afford.planning.tree import Node, Recognised, WorldModel
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
        out = []
        for k, parent in enumerate(parents):
            drawn = self.drawer.render(poses[k], int(held_next[k]))
            go = moved(before[k], poses[k])
            seen = self.seen[go & parent.state.as_seen].any(0)
            image = self.drawer.draw(parent.image, parent.state.drawn, drawn, seen)
            out.append((image, ObjectsState(poses[k], int(held_next[k]), drawn, parent.state.as_seen & ~go)))
        return out
