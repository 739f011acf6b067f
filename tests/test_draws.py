"""How generation picks each step's execution (data/draws.py), on a scripted scene where only
the block's turns have a side effect: a ball stands in the block's sweep, a cup far away."""

import numpy as np

from afford.data import effects as fx
from afford.data.draws import draw_seeking_effects, draw_uniform, pose_array
from afford.sim.affordance import encode_affordance
from afford.sim.affordances import parametrise
from afford.sim.constants import BALL
from afford.sim.scene import ObjectSpec as O

LAYOUT = [
    O.upright("block", 0, 0.30),
    O.upright("ball", 0.10, 0.30 + 0.03 + BALL.radius + 0.008),
    O.upright("cup", -0.15, 0.20),
]


def drawn(scene, draw, seed: int) -> tuple[str, fx.StepEffects]:
    """Reset to LAYOUT, draw one execution, and label what it left in the scene."""
    scene.reset(LAYOUT)
    names = tuple(n for n, _ in scene.slots)
    before = pose_array(scene)
    a, failed = draw(scene, parametrise(scene.affordances()), np.random.default_rng(seed))
    assert a is not None and failed == 0
    step = fx.step_effects(
        before,
        pose_array(scene),
        -1,
        names.index(scene.held) if scene.held else -1,
        encode_affordance(a),
        names,
    )
    return a.type, step


def test_seeking_keeps_an_execution_with_a_side_effect_that_uniform_draws_miss(scene):
    seeking = [drawn(scene, draw_seeking_effects, seed) for seed in range(3)]
    # The label is of the scene the draw left: the kept execution is the one carried out.
    assert all(kind == "turn" and not step.canonical for kind, step in seeking)
    uniform = [drawn(scene, draw_uniform, seed) for seed in range(6)]
    assert any(step.canonical for _, step in uniform)
