"""Every planner's plan judged the same way: executed in the simulator from the task's start,
open loop as the paper does (IV.C), and its success predicate read on the final true state.

Every planner's open-loop plan is handed here (the oracle's, the symbolic baselines', every
learned world model's), so a plan counts as solved by one rule whatever made it; a closed loop
executes as it plans (closed_loop.py) and reads the same predicate on the state it ends in.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from afford.sim.perturb import Perturbation, reset_perturbed
from afford.sim.scene import ObjectSpec, Scene


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
