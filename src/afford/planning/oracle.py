"""The oracle world model: the simulator itself as the "perfect model".

Recognition is the ground-truth detector, prediction is execution from a restored snapshot,
and the child's image is a real render. Plans found with it are the upper bound a learned
model is measured against (paper IV.C uses the learned model; this is our reference).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from afford.planning.tree import Node, Recognised, WorldModel
from afford.sim.affordance import Detection
from afford.sim.affordances import Affordance
from afford.sim.perturb import Perturbation, reset_perturbed
from afford.sim.scene import ObjectSpec, Scene


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


@dataclass
class Execution:
    """A plan carried out in the simulator from the task's start."""

    images: list[np.ndarray]  # the state after each step, the start first
    executed: list[bool]
    messages: list[str]
    success: bool


def execute_plan(
    scene: Scene,
    specs: list[ObjectSpec],
    plan,
    success,
    perturbation: Perturbation | None = None,
    rng: np.random.Generator | None = None,
    base: list[int] | None = None,
) -> Execution:
    """Reset to `specs`, execute `plan` open-loop as the paper does, judge `success` (a
    predicate) on the final true state. With `perturbation` the start is first moved by a
    draw from `rng` (`sim/perturb.py`; `base`: the start's piles, when already read): the plan
    meets a world a little unlike the one planned on."""
    if perturbation is None:
        scene.reset(specs)
    else:
        reset_perturbed(scene, specs, perturbation, rng if rng is not None else np.random.default_rng(), base)
    images, executed, messages = [scene.observe()], [], []
    for aff in plan:
        r = scene.execute(aff)
        executed.append(r.executed)
        messages.append(r.message)
        images.append(scene.observe())
    return Execution(images, executed, messages, bool(success.holds(scene)))
