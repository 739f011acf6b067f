"""Foresight (prediction/foresight.py) on hand-made cases: the truth scores 1, a copy of the input 0."""

import numpy as np
import pytest

from afford.data.effects import Effect, StepEffects, disks
from afford.prediction.foresight import Foresight, foresight_of


def images():
    rng = np.random.default_rng(0)
    before = rng.random((128, 128, 4)).astype(np.float32)  # (H, W, C), as the NumPy side holds images
    truth = before.copy()
    truth[50:70, 50:70] = rng.random((20, 20, 4))  # something changed here
    return before, truth


def test_the_truth_scores_one_and_a_copy_zero():
    before, truth = images()
    mask = np.zeros((128, 128), bool)
    mask[45:75, 45:75] = True
    assert foresight_of(truth, before, truth, mask) == pytest.approx(1.0)
    assert foresight_of(before, before, truth, mask) == pytest.approx(0.0)
    halfway = (before + truth) / 2
    assert foresight_of(halfway, before, truth, mask) == pytest.approx(0.5)
    assert foresight_of(1 - truth, before, truth, mask) < 0  # worse than no change


def test_nothing_changed_under_the_mask_gives_no_figure():
    before, truth = images()
    mask = np.zeros((128, 128), bool)
    mask[:10, :10] = True
    assert foresight_of(truth, before, truth, mask) is None


def test_disks_are_centred_on_the_projected_point():
    from afford.sim.camera import world_to_pixel

    point = np.array([0.05, 0.30, 0.02])
    mask = disks([point], radius=7)
    col, row = world_to_pixel(point)
    assert mask[int(row), int(col)]
    assert 140 <= mask.sum() <= 170  # pi * 7^2 = 154
    assert not mask[int(row) + 9, int(col)]


def test_groups_take_the_acted_on_object_and_the_side_effects_apart():
    before, _ = images()
    truth = before.copy()
    poses = np.full((2, 7), np.nan)
    poses[0] = [0.0, 0.25, 0.02, 1, 0, 0, 0]  # acted on
    poses[1] = [0.1, 0.35, 0.02, 1, 0, 0, 0]  # took a side effect
    after = poses.copy()
    predicted = before.copy()
    from afford.sim.camera import world_to_pixel

    for k in range(2):
        col, row = world_to_pixel(poses[k, :3]).astype(int)
        truth[row - 3 : row + 3, col - 3 : col + 3] = 0.0
    col, row = world_to_pixel(poses[0, :3]).astype(int)
    predicted[row - 3 : row + 3, col - 3 : col + 3] = 0.0  # only the acted-on object drawn
    step = StepEffects("turn", 0, (Effect("pushed", 1),))
    f = Foresight()
    f.add(step, np.array([2, 0, 0.25, 0.02, 0, 0, 90]), poses, after, predicted, before, truth)
    assert f.acted["turn"].foresight == pytest.approx(1.0)
    assert f.side["turn"].foresight == pytest.approx(0.0)
    assert f.kinds["pushed"].foresight == pytest.approx(0.0) and f.acted["grasp"].executions == 0


def test_an_effect_drawn_on_an_object_that_stayed_counts_against_the_still_objects():
    from afford.sim.camera import world_to_pixel

    before, _ = images()
    truth = before.copy()
    poses = np.full((3, 7), np.nan)
    poses[0] = [0.0, 0.25, 0.02, 1, 0, 0, 0]  # acted on
    poses[1] = [0.1, 0.35, 0.02, 1, 0, 0, 0]  # stays put
    col, row = world_to_pixel(poses[0, :3]).astype(int)
    truth[row - 3 : row + 3, col - 3 : col + 3] = 0.0
    step = StepEffects("grasp", 0, ())
    action = np.array([0, 0, 0.0, 0.25, 0.02, 0, 0])
    faithful, imagined = Foresight(), Foresight()
    faithful.add(step, action, poses, poses, truth, before, truth)
    drawn = truth.copy()
    col, row = world_to_pixel(poses[1, :3]).astype(int)
    drawn[row - 3 : row + 3, col - 3 : col + 3] = 1.0  # the still object drawn as if it moved
    imagined.add(step, action, poses, poses, drawn, before, truth)
    assert faithful.still["grasp"].error == pytest.approx(0.0)
    assert imagined.still["all"].error > 0.01 and imagined.still["turn"].executions == 0
    assert faithful.side["all"].executions == 0  # a canonical step has no side group


def test_a_side_effect_is_split_into_where_objects_leave_and_where_they_land():
    from afford.sim.camera import world_to_pixel

    before, _ = images()
    poses = np.full((2, 7), np.nan)
    poses[0] = [0.0, 0.25, 0.02, 1, 0, 0, 0]  # grasped
    poses[1] = [0.1, 0.35, 0.02, 1, 0, 0, 0]  # pushed ...
    after = poses.copy()
    after[1, :2] = [-0.1, 0.35]  # ... far across the table
    truth = before.copy()
    (c0, r0), (c1, r1) = world_to_pixel(poses[1, :3]).astype(int), world_to_pixel(after[1, :3]).astype(int)
    truth[r0 - 3 : r0 + 3, c0 - 3 : c0 + 3] = 0.0  # gone from where it stood
    truth[r1 - 3 : r1 + 3, c1 - 3 : c1 + 3] = 1.0  # there where it ended
    predicted = before.copy()
    predicted[r0 - 3 : r0 + 3, c0 - 3 : c0 + 3] = 0.0  # the leaving drawn, the landing not
    f = Foresight()
    step = StepEffects("grasp", 0, (Effect("pushed", 1),))
    f.add(step, np.zeros(7), poses, after, predicted, before, truth)
    assert f.parts["leaving"].foresight == pytest.approx(1.0)
    assert f.parts["landing"].foresight == pytest.approx(0.0)
    assert 0.0 < f.side["all"].foresight < 1.0
