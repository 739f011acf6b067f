"""Object perception with the shipped weights, on scripted scenes whose true state is known."""

from __future__ import annotations

import numpy as np
import pytest
from scenarios import block_on_support, do

from afford.errors import UserError
from afford.objects.perceive import perceive, to_state
from afford.objects.state import N_SLOTS, posture
from afford.shipped import Nets
from afford.sim.camera import world_to_pixel
from afford.sim.scene import ObjectSpec as O


@pytest.fixture(scope="module")
def net():
    return Nets().perception


def seen(net, scene):
    return perceive(net, scene.observe()[None])[0]


def near(objects, pos, kind):
    px = world_to_pixel(np.asarray(pos, dtype=float))
    mine = [o for o in objects if o.kind == kind and np.linalg.norm(o.pixel - px) < 3.0]
    assert len(mine) == 1, [(o.kind, o.pixel) for o in objects]
    return mine[0]


def test_two_cups_and_a_ball_are_found_where_they_stand(net, scene):
    scene.reset(
        [
            O.upright("cup", -0.1, 0.3),
            O.upright("cup", 0.1, 0.3),
            O.upright("ball", 0.0, 0.22),
        ]
    )
    objects = seen(net, scene)
    assert len(objects) == 3
    for truth in scene.objects():
        found = near(objects, truth.pos, truth.kind)
        assert found.posture == "upright"
        assert np.linalg.norm(found.position - truth.pos) < 0.01  # within a centimetre in 3D


def test_a_held_block_is_seen_held(net, scene):
    scene.reset([O.upright("block", 0.0, 0.3, 30.0), O.upright("cup", 0.15, 0.22)])
    do(scene, "grasp", (0.0, 0.3))
    assert scene.held == "block0"
    objects = seen(net, scene)
    block = [o for o in objects if o.kind == "block"]
    assert len(block) == 1 and block[0].held > 0.5
    poses, held = to_state(objects)
    assert held == N_SLOTS - 1  # the block's slot
    assert all(o.held < 0.5 for o in objects if o.kind != "block")


def test_an_image_of_the_wrong_size_is_one_line(net):
    with pytest.raises(UserError, match="128 x 128 RGBD"):
        perceive(net, np.zeros((1, 64, 64, 4), np.float32))


def test_a_cup_thrown_off_a_tipping_block_is_seen_lying_where_it_fell(net, scene):
    block_on_support(scene, -0.02, [O.upright("cup", 0.1, 0.2)])
    do(scene, "grasp", (0.1, 0.2))
    do(scene, "place", (0.09, 0.30))  # the overhang tips the block and the cup falls off
    cup = scene.object("cup0")
    assert cup.present and posture(cup.up_axis[2]) == "lying"
    assert near(seen(net, scene), cup.pos, "cup").posture == "lying"


def test_a_ball_hidden_under_a_block_is_not_seen_and_nothing_is_made_up(net, scene):
    scene.reset([O.upright("support", 0.0, 0.34), O.upright("ball", 0.09, 0.34), O.upright("block", 0, 0.22)])
    do(scene, "grasp", (0, 0.22))
    do(scene, "place", (0, 0.34), angle=90)  # the block's overhang covers the ball
    assert scene.object("ball0").present and scene.visible_pixels("ball0") == 0
    objects = seen(net, scene)
    assert [o.kind for o in objects] == ["block"]  # the support under it is hidden too
    near(objects, scene.object("block0").pos, "block")
