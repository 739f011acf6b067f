"""The planner's world model that separates the costs of perception and of learned dynamics:
the oracle's search (`oracle.py`) over a simulator scene built from the objects the perception
net sees in the start image (`objects/simulated.py`)."""

from __future__ import annotations

import numpy as np

from afford.objects.simulated import scene_from_state
from afford.planning.oracle import OracleModel
from afford.sim.scene import Scene


class PerceivedSimModel(OracleModel):
    """The planner's world model (`--planner perceived-sim`): the oracle's search over a scene
    built from what the perception net sees in the start image."""

    def __init__(self, image: np.ndarray, perception, scene: Scene | None = None) -> None:
        """`scene`: the simulator to build the perceived state in (a new one by default; it
        must not be the one the plan is executed in)."""
        from afford.objects.perceive import perceive, to_state

        poses, held = to_state(perceive(perception, image[None])[0])
        scene = scene if scene is not None else Scene()
        scene_from_state(scene, poses, held)
        super().__init__(scene)
