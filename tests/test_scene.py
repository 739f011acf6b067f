"""Scenes by seed, snapshots, JSON, and the camera model."""

import itertools
import json

import mujoco
import numpy as np
import pytest
from scenarios import do

from afford.sim.affordances import Affordance, parametrise
from afford.sim.camera import pixel_to_world, world_to_pixel
from afford.sim.constants import BLOCK
from afford.sim.layout import random_layout
from afford.sim.scene import ObjectSpec as O
from afford.sim.scene import SceneError, specs_from_json, specs_to_json


@pytest.mark.parametrize("seed", range(12))
def test_random_scene_compiles_steps_and_executes_without_warnings(scene, seed):
    rng = np.random.default_rng(seed)
    scene.reset(random_layout(rng))
    for _ in range(2):
        affs = parametrise(scene.affordances())
        if not affs:
            break
        scene.execute(affs[int(rng.integers(len(affs)))])
    warnings = {
        mujoco.mjtWarning(i).name: int(scene.data.warning[i].number) for i in range(len(scene.data.warning))
    }
    assert not any(warnings.values()), warnings
    image = scene.observe()
    assert image.shape == (128, 128, 4) and image.dtype == np.float32
    assert 0.0 <= image.min() and image.max() <= 1.0


def test_random_layout_is_deterministic():
    a = random_layout(np.random.default_rng(5))
    b = random_layout(np.random.default_rng(5))
    assert a == b and len([s for s in a if s.kind == "block"]) == 1


def test_snapshot_restore_gives_identical_execution(scene):
    scene.reset(
        [O.upright("block", 0, 0.30), O.upright("ball", 0.09, 0.30, z=0.05), O.upright("cup", 0.1, 0.375)]
    )
    snap = scene.snapshot()
    turn = [a for a in scene.affordances() if a.type == "turn"][0].with_turn(90)
    results = []
    for _ in range(2):
        scene.restore(snap)
        scene.execute(turn)
        results.append(
            np.concatenate([np.concatenate([o.pos, o.quat]) for o in scene.objects(present_only=False)])
        )
    np.testing.assert_array_equal(results[0], results[1])


def test_parked_objects_are_hidden_from_the_camera_and_a_restored_one_is_seen_again(scene):
    from afford.sim.mjcf import HIDDEN_GROUP

    scene.reset([O.upright("cup", 0.0, 0.30)])
    snap, image = scene.snapshot(), scene.observe()
    cup0 = scene.model.geom_bodyid == scene.model.body("cup0").id
    cup1 = scene.model.geom_bodyid == scene.model.body("cup1").id
    assert np.all(scene.model.geom_group[cup1] == HIDDEN_GROUP)  # parked: not drawn
    assert np.all(scene.model.geom_group[cup0] != HIDDEN_GROUP)
    scene.model.geom_group[:] = scene._geom_group0  # every slot drawn, the parked ones too
    np.testing.assert_array_equal(scene._camera.render(scene.data), image)  # out of view: the same
    scene.reset([])
    assert not np.array_equal(scene.observe(), image)  # the cup parked: an empty table
    scene.restore(snap)  # the cup back on the table by a snapshot, not by reset
    np.testing.assert_array_equal(scene.observe(), image)
    assert (scene.instance_mask() == 0).sum() > 50


def test_json_round_trip_and_errors(scene, tmp_path):
    scene.reset([O.upright("block", 0, 0.30, 20), O.upright("cup", 0.1, 0.2)])
    specs = scene.specs()
    again = specs_from_json(json.loads(json.dumps(specs_to_json(specs))))
    assert [s.kind for s in again] == [s.kind for s in specs]
    np.testing.assert_allclose([s.pos for s in again], [s.pos for s in specs])
    for bad, field in [
        ({"objects": [{"kind": "mug", "pos": [0, 0, 0]}]}, "objects[0].kind"),
        ({"objects": [{"kind": "cup", "pos": [0, 0]}]}, "objects[0].pos"),
        ({"objects": [{"kind": "cup", "pos": [0, 0, 0], "quat": [0, 0, 0, 0]}]}, "objects[0].quat"),
        ({"objects": "cup"}, "objects"),
        ([], "scene"),
    ]:
        with pytest.raises(SceneError, match=field.replace("[", r"\[").replace("]", r"\]")):
            specs_from_json(bad)
    with pytest.raises(SceneError, match="at most 3"):
        scene.reset([O.upright("cup", 0.1 * i - 0.2, 0.2) for i in range(4)])


def test_pixel_world_round_trip_and_projection_of_a_ball(scene):
    pts = np.array([[0.1, 0.2, 0.0], [-0.15, 0.4, 0.08]])
    px = world_to_pixel(pts)
    depth = (0.70 - pts[:, 2] - 0.15) / (0.75 - 0.15)
    np.testing.assert_allclose(pixel_to_world(px, depth), pts, atol=1e-9)
    scene.reset([O.upright("ball", 0.12, 0.22), O.upright("block", -0.05, 0.35)])
    image = scene.observe()
    col, row = world_to_pixel(scene.object("ball0").pos).astype(int)
    assert image[row, col, 0] > 0.7 and image[row, col, 1] < 0.3  # red where the ball projects
    top = scene.object("ball0").pos + [0, 0, 0.025]
    z = pixel_to_world(np.array([col + 0.5, row + 0.5]), image[row, col, 3])[2]
    assert abs(z - top[2]) < 0.005  # depth reads the ball's top


ROBOT_BODIES = ("link1", "link2", "link3", "link4", "link5", "link6", "hand", "finger_l", "finger_r")


def _arm_region(scene) -> np.ndarray:
    """The pixels around the arm at home: its bounding box in the image, 4 px wider each way."""
    robot = [scene.model.body(n).id for n in ROBOT_BODIES]
    rows, cols = np.nonzero(np.isin(scene._cam().segment(scene.data), robot))
    region = np.zeros((128, 128), dtype=bool)
    region[max(0, rows.min() - 4) : rows.max() + 5, max(0, cols.min() - 4) : cols.max() + 5] = True
    return region


def _objects_seen(scene) -> np.ndarray:
    """Pixels showing an object, grown by 2 px: edge pixels blend the colours either side."""
    objects = [scene.body_id(n) for n, _ in scene.slots]
    seen = np.isin(scene._cam().segment(scene.data), objects)
    grown = seen.copy()
    for dr in range(-2, 3):
        for dc in range(-2, 3):
            grown |= np.roll(seen, (dr, dc), (0, 1))
    return grown


def test_home_pose_renders_identically_after_any_execution(scene):
    # Two different scenes: one fresh, one after a grasp, a failed grasp and a place. With
    # nothing held, every pixel around the arm that shows no object must be identical.
    scene.reset([O.upright("cup", 0.12, 0.30), O.upright("support", -0.12, 0.32)])
    fresh, fresh_objects, region = scene.observe(), _objects_seen(scene), _arm_region(scene)
    scene.reset(
        [O.upright("ball", -0.05, 0.36), O.upright("support", 0.10, 0.28), O.upright("block", 0, 0.42)]
    )
    air = scene.execute(Affordance("grasp", (-0.2, 0.40, 0.03), 30.0, True))  # the fingers close on air
    assert air.executed and scene.held is None
    do(scene, "grasp", (-0.05, 0.36))
    do(scene, "place", (0.10, 0.28))
    assert scene.held is None
    after = scene.observe()
    compare = region & ~fresh_objects & ~_objects_seen(scene)
    assert compare.sum() > 200
    np.testing.assert_array_equal(after[compare], fresh[compare])


@pytest.mark.parametrize("where", [(0.0, 0.28), (0.0, 0.18), (-0.18, 0.40), (0.18, 0.16)])
def test_a_support_under_the_block_shows_at_any_yaw_of_either(scene, where):
    """The support that decides whether the block tips is seen (paper III.B): its foot shows
    beside the block wherever the block rests on it. Nearest the camera's axis the block's top,
    11 cm up, is drawn widest over the foot: the hardest place."""
    from afford.sim.layout import SUPPORT_TOP, _yaw_quat

    for block_yaw, support_yaw, along in itertools.product((0, 30, 45, 90), (0, 20, 45, 70), (-0.02, 0.02)):
        u = np.array([np.cos(np.radians(block_yaw)), np.sin(np.radians(block_yaw))])
        sx, sy = np.array(where) + u * along
        block = O("block", (*where, SUPPORT_TOP + BLOCK.half[2]), _yaw_quat(np.radians(block_yaw)))
        scene.reset([O.upright("support", sx, sy, support_yaw), block], settle=False, check=False)
        mujoco.mj_forward(scene.model, scene.data)
        shown = scene.visible_pixels("support0")
        assert shown >= 30, (block_yaw, support_yaw, along, shown)
