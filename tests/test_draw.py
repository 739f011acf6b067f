"""D over objects: states drawn from the current image and the objects' next states."""

from __future__ import annotations

import numpy as np
import pytest
from scenarios import SUPPORT_TOP

from afford.data.draws import pose_array
from afford.objects.draw import Drawer
from afford.sim.scene import ObjectSpec


@pytest.fixture(scope="module")
def drawer():
    d = Drawer()
    yield d
    d.scene.close()


def state_of(scene):
    held = [name for name, _ in scene.slots].index(scene.held) if scene.held else -1
    return pose_array(scene), held


def test_a_shifted_ball_is_drawn_where_it_went_and_nothing_else_changes(drawer, scene):
    scene.reset([ObjectSpec.upright("ball", -0.05, 0.3), ObjectSpec.upright("cup", 0.12, 0.22)])
    image = scene.observe()
    poses, held = state_of(scene)
    moved = poses.copy()
    ball = [name for name, _ in scene.slots].index("ball0")
    moved[ball, 0] += 0.06  # 6 cm along x, still on the flat table
    drawn = drawer.draw(image, drawer.render(poses, held), drawer.render(moved, held))

    specs = [
        ObjectSpec(kind, tuple(moved[k, :3]), tuple(moved[k, 3:]))
        for k, (_, kind) in enumerate(scene.slots)
        if not np.isnan(moved[k, 0])
    ]
    scene.reset(specs, settle=False, check=False)  # the true render of the moved state
    truth = scene.observe()
    # pixel for pixel (the truth is rendered from float32 poses: depth agrees to 1e-6)
    np.testing.assert_allclose(drawn, truth, rtol=0, atol=1e-6)
    changed = np.abs(drawn - image).max(-1) > 0
    seg_before = drawer.scene.instance_mask()  # the drawer's last render: the moved state
    assert changed.any() and np.all(changed <= (seg_before == ball) | (np.abs(truth - image).max(-1) > 0))
    cup_pixels = scene.instance_mask() == [n for n, _ in scene.slots].index("cup0")
    np.testing.assert_array_equal(drawn[cup_pixels], image[cup_pixels])  # the cup untouched


def test_a_moved_object_seen_off_its_pose_leaves_nothing_behind(drawer, scene):
    scene.reset([ObjectSpec.upright("ball", -0.05, 0.3), ObjectSpec.upright("cup", 0.12, 0.22)])
    image = scene.observe()
    ball = [name for name, _ in scene.slots].index("ball0")
    real = scene.instance_mask() == ball
    poses, held = state_of(scene)
    perceived = poses.copy()
    perceived[ball, 0] += 0.015  # seen 3 px off where it is, more than the mask's widening
    away = perceived.copy()
    away[ball, 0] += 0.08
    now, after = drawer.render(perceived, held), drawer.render(away, held)
    # from the drawings alone, a rim of the real ball stays where it was
    assert np.abs(drawer.draw(image, now, after)[real] - after[real]).max() > 0.1
    # with the pixels the ball was seen in, every one of them shows the next state
    drawn = drawer.draw(image, now, after, seen=real)
    np.testing.assert_array_equal(drawn[real], after[real])
    cup_pixels = scene.instance_mask() == [n for n, _ in scene.slots].index("cup0")
    np.testing.assert_array_equal(drawn[cup_pixels], image[cup_pixels])


def test_an_object_moved_under_another_stays_hidden(drawer, scene):
    # The block rests on a support at one end; its other end overhangs the table.
    specs = [
        ObjectSpec.upright("support", 0.1, 0.3),
        ObjectSpec.upright("block", 0.0, 0.3, 0.0, z=SUPPORT_TOP),
        ObjectSpec.upright("ball", -0.05, 0.2),
    ]
    scene.reset(specs, check=False)
    image = scene.observe()
    poses, held = state_of(scene)
    ball = [name for name, _ in scene.slots].index("ball0")
    block = [name for name, _ in scene.slots].index("block0")
    under = poses.copy()
    under[ball, :2] = poses[block, :2] + np.array([-0.08, 0.0])  # beneath the overhang
    drawn = drawer.draw(image, drawer.render(poses, held), drawer.render(under, held))
    seen = drawer.scene.instance_mask()
    assert (seen == ball).sum() < 5  # the renderer's depth test hides it
    block_pixels = seen == block
    np.testing.assert_array_equal(drawn[block_pixels], drawer.scene.observe()[block_pixels])
    assert (np.abs(drawn - image).max(-1) > 0).sum() > 20  # the ball left where it was


def test_the_true_next_state_draws_the_recorded_image(drawer, small_dataset):
    from afford.data.format import Dataset

    seq = Dataset(small_dataset).sequence(0)
    for t in range(seq.length):
        now = drawer.render(seq.poses[t], int(seq.held[t]))
        nxt = drawer.render(seq.poses[t + 1], int(seq.held[t + 1]))
        drawn = drawer.draw(seq.image(t), now, nxt)
        assert np.abs(drawn - seq.image(t + 1)).max() < 2e-3  # the stored images are quantised


def test_an_object_sunk_into_what_it_landed_on_is_lifted_to_rest_on_it(drawer, scene):
    from scenarios import BLOCK_TOP_ON_SUPPORT

    scene.reset(
        [
            ObjectSpec.upright("support", 0.0, 0.30),
            ObjectSpec.upright("block", 0.0, 0.30, 0.0, z=SUPPORT_TOP),
            ObjectSpec.upright("cup", -0.08, 0.30, z=BLOCK_TOP_ON_SUPPORT),
            ObjectSpec.upright("ball", 0.12, 0.20),
        ]
    )
    poses, held = state_of(scene)
    slots = [name for name, _ in scene.slots]
    cup, ball, block = slots.index("cup0"), slots.index("ball0"), slots.index("block0")
    sunk = poses.copy()
    sunk[cup, 2] -= 0.006  # 6 mm into the block, as a dynamics' landing a little low
    sunk[ball, 2] -= 0.004  # sunk into the table, but not moved: left as it is
    moved = np.zeros(len(poses), bool)
    moved[cup] = True
    rested = drawer.rest(sunk, held, moved)
    assert rested[cup, 2] == pytest.approx(poses[cup, 2], abs=1e-3)
    np.testing.assert_array_equal(rested[ball], sunk[ball])
    np.testing.assert_array_equal(rested[block], sunk[block])
    np.testing.assert_array_equal(drawer.rest(poses, held, moved), poses)  # resting: nothing to lift
