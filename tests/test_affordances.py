"""The ground-truth affordance detector (paper III.B)."""

import numpy as np
from scenarios import do

from afford.sim.affordances import Affordance, parametrise
from afford.sim.constants import BALL, CUP
from afford.sim.scene import ObjectSpec as O


def at(affs, x, y, tol=0.01):
    return [a for a in affs if np.hypot(a.position[0] - x, a.position[1] - y) < tol]


def test_empty_gripper_has_no_place_and_holding_has_no_grasp_or_turn(scene):
    scene.reset(
        [O.upright("support", 0.12, 0.38), O.upright("cup", -0.1, 0.22), O.upright("block", 0, 0.30, 90)]
    )
    types = {a.type for a in scene.affordances()}
    assert types == {"grasp", "turn"}
    do(scene, "grasp", (-0.1, 0.22))
    assert {a.type for a in scene.affordances()} == {"place"}


def test_symmetric_objects_get_quarter_turns_and_block_one_angle(scene):
    scene.reset(
        [O.upright("cup", -0.1, 0.22), O.upright("ball", 0.12, 0.22), O.upright("block", 0, 0.40, 30)]
    )
    affs = scene.affordances()
    for x, y in ((-0.1, 0.22), (0.12, 0.22)):
        grasps = at(affs, x, y)
        assert sorted(a.angle for a in grasps) == [0.0, 90.0, 180.0, 270.0]
        assert all(a.symmetric for a in grasps)
    block = at(affs, 0, 0.40)
    assert sorted(a.type for a in block) == ["grasp", "turn"]
    assert all(abs(a.angle - 120.0) < 0.5 and not a.symmetric for a in block)  # across the block


def test_boxed_in_object_loses_colliding_grasp_angles(scene):
    gap = BALL.radius + CUP.radius + 0.01
    scene.reset(
        [
            O.upright("ball", 0, 0.28),
            O.upright("cup", -gap, 0.28),
            O.upright("cup", gap, 0.28),
            O.upright("block", 0, 0.42),
        ]
    )
    angles = sorted(a.angle for a in at(scene.affordances(), 0, 0.28) if a.type == "grasp")
    assert angles == [90.0, 270.0]  # fingers opening along x would hit the cups


def test_out_of_reach_object_has_no_affordance(scene):
    scene.reset([O.upright("ball", 0.30, 0.58), O.upright("block", 0, 0.30)])
    assert scene.object("ball0").present
    assert at(scene.affordances(), 0.30, 0.58) == []


def test_place_needs_free_space(scene):
    scene.reset(
        [
            O.upright("support", 0.12, 0.38),
            O.upright("cup", 0.12, 0.38, z=0.06),
            O.upright("ball", -0.1, 0.22),
            O.upright("block", 0, 0.28, 0),
        ]
    )
    do(scene, "grasp", (-0.1, 0.22))
    places = [a for a in scene.affordances() if a.type == "place"]
    assert at(places, 0.12, 0.38) == []  # the cup occupies the support
    assert len(at(places, 0.0, 0.28)) == 4  # the free middle of the block, at quarter turns


def test_parametrise_turns_and_round_trip():
    a = Affordance("turn", (0.0, 0.3, 0.02), 90.0, False)
    assert [b.turn for b in parametrise([a])] == [90, -90]
    b = Affordance.from_dict(a.with_turn(-90).to_dict())
    assert b == a.with_turn(-90)


def test_a_turn_takes_any_angle_up_to_a_half_turn_and_no_more():
    import pytest

    from afford.sim.affordances import Affordance

    a = Affordance("turn", (0.0, 0.3, 0.03), 0.0, False, 37.5)
    assert Affordance.from_dict(a.to_dict()) == a
    for bad in (181.0, float("nan")):
        with pytest.raises(ValueError, match=r"\[-180, 180\]"):
            Affordance("turn", (0.0, 0.3, 0.03), 0.0, False, bad)
