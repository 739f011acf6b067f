"""The oracle world model: the simulator itself as the "perfect model".

Recognition is the ground-truth detector, prediction is execution from a restored snapshot,
and the child's image is a real render. Plans found with it are the upper bound a learned
model is measured against (paper IV.C uses the learned model; this is our reference).
"""

from __future__ import annotations

from afford.planning.tree import Node, Recognised, WorldModel
from afford.sim.affordance import Detection
from afford.sim.affordances import Affordance
from afford.sim.scene import Scene


class OracleModel(WorldModel):
    """A `WorldModel` backed by a `Scene`, started from the state the caller put it in."""

    def __init__(self, scene: Scene):
        self.scene = scene
        self._root = scene.snapshot()

    def root(self):
        self.scene.restore(self._root)
        return self.scene.observe(), self._root

    def recognise(self, nodes: list[Node]) -> list[Recognised]:
        out = []
        for n in nodes:
            self.scene.restore(n.state)
            out.append([Detection(a) for a in self.scene.affordances()])
        return out

    def predict(self, parents: list[Node], actions: list[Affordance]):
        out = []
        for parent, action in zip(parents, actions, strict=True):
            self.scene.restore(parent.state)
            if not self.scene.execute(action).executed:
                out.append(None)
                continue
            out.append((self.scene.observe(), self.scene.snapshot()))
        return out
