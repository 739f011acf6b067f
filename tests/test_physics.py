"""The paper's non-canonical effects (III.A), each on a scripted scene, asserted on true poses."""

import numpy as np
from scenarios import BLOCK_TOP_ON_SUPPORT, BLOCK_TOP_ON_TABLE, SUPPORT_TOP, block_on_support, do, find

from afford.sim.constants import BALL, CUP
from afford.sim.layout import _yaw_quat
from afford.sim.scene import ObjectSpec as O

BESIDE = 0.30 + 0.03 + CUP.radius + 0.008  # just clear of the block's long side


def on_table(o) -> bool:
    return o.present and o.pos[2] < 0.05


def test_a_turning_block_knocks_over_nearby_cup(scene):
    # Toppling needs the block's top edge to meet the tapered wall: from most other spots
    # beside the block the cup is shoved instead (the next test).
    scene.reset([O.upright("block", 0, 0.30), O.upright("cup", 0.11, BESIDE + 0.004)])
    do(scene, "turn", (0, 0.30), turn=90)
    assert scene.object("cup0").up_axis[2] < 0.5


def test_a_turning_block_shoves_nearby_cup(scene):
    scene.reset([O.upright("block", 0, 0.30), O.upright("cup", 0.10, BESIDE)])
    do(scene, "turn", (0, 0.30), turn=90)
    assert np.linalg.norm(scene.object("cup0").pos[:2] - [0.10, BESIDE]) > 0.05


def test_b_turning_block_pushes_ball_away(scene):
    scene.reset([O.upright("block", 0, 0.30), O.upright("ball", 0.10, 0.30 + 0.03 + BALL.radius + 0.008)])
    do(scene, "turn", (0, 0.30), turn=90)
    ball = scene.object("ball0")
    assert not ball.present or np.linalg.norm(ball.pos[:2] - [0.10, 0.363]) > 0.10


def test_c_ball_on_block_rolls_off_when_turned(scene):
    scene.reset([O.upright("block", 0, 0.30), O.upright("ball", 0.09, 0.30, z=BLOCK_TOP_ON_TABLE)])
    assert scene.object("ball0").pos[2] > BLOCK_TOP_ON_TABLE  # it starts on the block
    do(scene, "turn", (0, 0.30), turn=90)
    ball = scene.object("ball0")
    assert not ball.present or ball.pos[2] < BALL.radius + 0.005  # on the table or gone


def test_d_cup_on_block_turns_with_it(scene):
    scene.reset([O.upright("block", 0, 0.30), O.upright("cup", 0.09, 0.30, z=BLOCK_TOP_ON_TABLE)])
    do(scene, "turn", (0, 0.30), turn=90)
    cup = scene.object("cup0")
    # +90 is counter-clockwise: the point 9 cm along +x ends 9 cm along +y, still on the block.
    np.testing.assert_allclose(cup.pos[:2], [0.0, 0.39], atol=0.015)
    assert cup.pos[2] > BLOCK_TOP_ON_TABLE and cup.up_axis[2] > 0.95


def test_d2_a_turn_by_any_angle_turns_the_block_and_its_cup_by_that_angle(scene):
    # Continuous turns (paper V): the same turn, by 45 degrees.
    scene.reset([O.upright("block", 0, 0.30), O.upright("cup", 0.09, 0.30, z=BLOCK_TOP_ON_TABLE)])
    do(scene, "turn", (0, 0.30), turn=45.0)
    cup = scene.object("cup0")
    np.testing.assert_allclose(
        cup.pos[:2], [0.09 * np.cos(np.pi / 4), 0.30 + 0.09 * np.sin(np.pi / 4)], atol=0.015
    )
    assert cup.up_axis[2] > 0.95


def test_e_lifting_block_throws_off_object_on_it(scene):
    scene.reset([O.upright("block", 0, 0.30), O.upright("cup", 0.09, 0.30, z=BLOCK_TOP_ON_TABLE)])
    do(scene, "grasp", (0, 0.30))
    assert scene.held == "block0"
    cup = scene.object("cup0")
    assert not cup.present or on_table(cup)


def test_f_place_on_overhang_tips_block_and_object_falls(scene):
    block_on_support(scene, -0.02, [O.upright("cup", 0.1, 0.2)])
    do(scene, "grasp", (0.1, 0.2))
    do(scene, "place", (0.09, 0.30))
    cup, block = scene.object("cup0"), scene.object("block0")
    assert not cup.present or on_table(cup)
    assert block.up_axis[2] < 0.99 or block.pos[2] < SUPPORT_TOP  # the block tipped


def test_g_counterbalance_makes_same_place_stable(scene):
    block_on_support(
        scene, -0.02, [O.upright("cup", 0.1, 0.2), O.upright("ball", -0.09, 0.30, z=BLOCK_TOP_ON_SUPPORT)]
    )
    do(scene, "grasp", (0.1, 0.2))
    do(scene, "place", (0.09, 0.30))
    cup, block = scene.object("cup0"), scene.object("block0")
    np.testing.assert_allclose(cup.pos[:2], [0.09, 0.30], atol=0.02)
    assert cup.pos[2] > BLOCK_TOP_ON_SUPPORT and block.up_axis[2] > 0.99


def test_h_ball_placed_on_sloped_block_rolls_away(scene):
    pitch = -np.arctan2(SUPPORT_TOP, 2 * (0.14 - 0.02))
    scene.reset(
        [
            O.upright("support", 0.12, 0.30),
            O("block", (0, 0.30, SUPPORT_TOP / 2 + 0.029), _yaw_quat(0, pitch)),  # as layouts prop it
            O.upright("ball", -0.1, 0.2),
        ]
    )
    assert scene.object("block0").up_axis[2] < 0.995  # the block lies at a slope
    do(scene, "grasp", (-0.1, 0.2))
    place = find(scene.affordances(), "place", (0.09, 0.30))
    scene.execute(place)
    ball = scene.object("ball0")
    assert not ball.present or np.linalg.norm(ball.pos[:2] - place.position[:2]) > 0.1


def red_pixels(image) -> int:
    return int(((image[..., 0] > 0.7) & (image[..., 1] < 0.3) & (image[..., 2] < 0.3)).sum())


def test_i_block_overhang_hides_ball(scene):
    scene.reset([O.upright("support", 0.0, 0.34), O.upright("ball", 0.09, 0.34), O.upright("block", 0, 0.22)])
    assert red_pixels(scene.observe()) > 20
    do(scene, "grasp", (0, 0.22))
    do(scene, "place", (0, 0.34), angle=90)  # keeps the block along x, over the ball
    assert scene.object("ball0").present
    assert red_pixels(scene.observe()) == 0
    assert not any(
        a.type == "grasp" and np.hypot(a.position[0] - 0.09, a.position[1] - 0.34) < 0.02
        for a in scene.affordances()
    )  # the block above leaves no room for the gripper


def test_canonical_grasp_then_place_moves_object_to_place_point(scene):
    scene.reset(
        [O.upright("support", 0.12, 0.38), O.upright("cup", -0.1, 0.22), O.upright("block", 0, 0.30, 90)]
    )
    do(scene, "grasp", (-0.1, 0.22))
    assert scene.held == "cup0"
    do(scene, "place", (0.12, 0.38))
    cup = scene.object("cup0")
    assert scene.held is None
    np.testing.assert_allclose(cup.pos, [0.12, 0.38, SUPPORT_TOP + CUP.height / 2], atol=0.01)
    assert cup.up_axis[2] > 0.99


def test_j_the_block_rests_and_tips_on_the_post_not_on_the_foot(scene):
    """A support is a post on a wide foot plate: the block's statics are the post's top (5 cm),
    so a bare block 2 cm off the post's centre stays level and one 3.5 cm off tips as it settles,
    though the foot (9 cm) reaches under it."""
    block_on_support(scene, -0.02, [])
    assert scene.object("block0").up_axis[2] > 0.999
    block_on_support(scene, -0.035, [])
    block = scene.object("block0")
    assert block.up_axis[2] < 0.99 or block.pos[2] < SUPPORT_TOP
