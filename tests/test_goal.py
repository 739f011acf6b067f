"""The goal loss of eq. (5) and the choice of eq. (4), on hand-made images."""

import numpy as np
import pytest

from afford.planning.goal import Goal, GoalError, window_mse


def test_window_mse_matches_brute_force():
    rng = np.random.default_rng(0)
    states = rng.random((19, 20, 24, 4))  # more states than are computed at once
    patch = rng.random((5, 7, 4))
    fast = window_mse(patch, states)
    assert fast.shape == (19, 16, 18)
    for b, y, x in [(0, 0, 0), (1, 15, 17), (0, 7, 3), (18, 4, 9), (9, 15, 0)]:
        brute = ((states[b, y : y + 5, x : x + 7] - patch) ** 2).mean()
        assert fast[b, y, x] == pytest.approx(brute, abs=1e-9)


def test_patch_is_found_at_its_true_offset():
    rng = np.random.default_rng(1)
    state = rng.random((64, 64, 4))
    patch = state[23:35, 40:50].copy()
    mse = window_mse(patch, state[None])[0]
    assert np.unravel_index(mse.argmin(), mse.shape) == (23, 40)
    assert Goal(patch).loss(state[None])[0] == pytest.approx(0.0, abs=1e-9)


def test_rgb_goal_ignores_depth():
    state = np.zeros((1, 32, 32, 4))
    state[0, 10:14, 10:14, 0] = 1.0
    patch = state[0, 8:16, 8:16, :3].copy()
    moved_up = state.copy()
    moved_up[..., 3] = 0.7  # the same picture, nearer the camera
    assert Goal(patch).loss(moved_up)[0] == pytest.approx(0.0, abs=1e-9)
    assert Goal(state[0, 8:16, 8:16].copy()).loss(moved_up)[0] > 0.1


def test_negative_goal_picks_the_state_without_the_object():
    with_ball = np.zeros((32, 32, 4))
    with_ball[5:9, 20:24, 0] = 1.0
    without = np.zeros((32, 32, 4))
    moved = np.zeros((32, 32, 4))
    moved[20:24, 3:7, 0] = 1.0
    patch = with_ball[3:11, 18:26, :3].copy()
    states = np.stack([with_ball, moved, without])
    losses = Goal(patch, negative=True).loss(states)
    assert Goal(patch, negative=True).best(losses) == 2  # argmax: the ball is gone
    assert Goal(patch).best(losses) in (0, 1)  # argmin: the ball is there (anywhere)


def test_goal_validation():
    with pytest.raises(GoalError, match="3\\) or"):
        Goal(np.zeros((4, 4, 2)))
    with pytest.raises(GoalError, match=r"\[0, 1\]"):
        Goal(np.full((4, 4, 3), 2.0))
    with pytest.raises(GoalError, match="larger"):
        window_mse(np.zeros((40, 4, 3)), np.zeros((1, 32, 32, 3)))
