"""How unsure a prediction is: the ensemble's total variance, a two-outcome net's own, and
plans scored by their spread (paper V)."""

import numpy as np
import pytest
import torch
from test_hypotheses import TINY

from afford.planning.uncertain import risk_score
from afford.prediction.ensemble import outcome_variance, total_variance
from afford.prediction.model import PredictionNet
from afford.training.fields import with_fields


def test_the_spread_is_zero_when_members_agree_and_are_sure():
    means = torch.rand(1, 4, 8, 8).expand(3, 4, 8, 8)
    assert torch.all(total_variance(means, torch.zeros(3, 8, 8)) == 0)
    own = torch.full((3, 8, 8), 0.01)
    parted = means + torch.randn(3, 1, 8, 8) * 0.1
    assert torch.allclose(total_variance(means, own), own[0])
    assert torch.all(total_variance(parted, own) > 0.01)


def test_the_expected_score_prefers_the_plan_whose_members_agree():
    """Two plans of equal mean loss: the one whose members part scores worse for a positive
    goal (and better for a negative one); a member's own variance counts as a spread does."""
    agree = np.array([[0.2], [0.2], [0.2]])
    part = np.array([[0.1], [0.2], [0.3]])
    losses = np.concatenate([agree, part], 1)
    score, spread = risk_score(losses, 1.0, negative=False)
    assert spread[0] == pytest.approx(0.0, abs=1e-12) and score[0] < score[1]
    assert risk_score(losses, 1.0, negative=True)[0][0] > risk_score(losses, 1.0, negative=True)[0][1]
    within = np.array([[0.0, 0.0], [0.0, 0.0], [0.0, 0.01]])
    assert risk_score(agree.repeat(2, 1), 1.0, False, within)[0][1] > 0.2


def test_the_variance_calibration_fits_a_scale_on_val(small_dataset):
    from afford.data.format import Dataset
    from afford.prediction.ensemble import calibrate

    torch.manual_seed(0)
    net = PredictionNet(with_fields(TINY, hypotheses=2, hypotheses_by="effect", fork="latent"))
    cal = calibrate([net], Dataset(small_dataset), "train", batch=4)
    assert len(cal.variance) == len(cal.squared) == len(cal.step) > 0 and np.all(cal.variance > 0)
    assert cal.ratio(cal.fitted_scale()) == pytest.approx(1.0, rel=1e-6)
    assert sum(b["pixels"] for b in cal.reliability(4)) == len(cal.pixel_variance)


def test_two_outcomes_give_the_variance_of_the_truth_about_the_one_drawn():
    drawn = torch.rand(2, 4, 8, 8)
    other = drawn + 0.2  # every channel of every pixel 0.2 away
    candidates = torch.stack([drawn, other], 1)  # (B, K, C, H, W): the first is the one drawn
    probability = torch.tensor([[0.75, 0.25], [1.0, 0.0]])
    variance = outcome_variance(candidates, probability, drawn)
    assert variance.shape == (2, 8, 8)
    assert torch.allclose(variance[0], torch.full((8, 8), 0.25 * 0.04))
    assert torch.all(variance[1] == 0)  # sure of the one drawn
