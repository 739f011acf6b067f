"""A variance beside D's image (prediction/variance.py) and plans scored by it (paper V)."""

import numpy as np
import pytest
import torch
from test_hypotheses import place_rows, two_outcomes

from afford.planning.goal import Goal
from afford.planning.uncertain import QUADRATURE, quadrature_losses, risk_score
from afford.prediction.config import PRESETS
from afford.prediction.model import PredictionNet
from afford.prediction.train import make_optimizer, sequence_loss
from afford.prediction.variance import LOG_VARIANCE_RANGE, beta_nll, outcome_variance, total_variance
from afford.training.checkpoint import load_model_state
from afford.training.fields import with_fields

TINY = PRESETS["tiny"]
WITH_HEAD = with_fields(TINY, variance=True, loss_nll=1.0)


def test_beta_nll_gradient_by_hand():
    """One pixel of 2 channels, errors 0.3 and 0.4 (squared 0.25), log sigma^2 = -1, beta 0.5:
    d/dlv of w * 0.5 (2 lv + 0.25 e^-lv) with w = e^(0.5 lv) held fixed is w * 0.5 (2 - 0.25 e^-lv);
    the mean gets none."""
    mean = torch.zeros(2, 1, 1, requires_grad=True)
    truth = torch.tensor([0.3, 0.4]).view(2, 1, 1)
    log_var = torch.full((1, 1, 1), -1.0, requires_grad=True)
    loss = beta_nll(mean, log_var, truth, beta=0.5).sum()
    loss.backward()
    w = np.exp(-0.5)
    assert loss.item() == pytest.approx(w * 0.5 * (2 * -1.0 + 0.25 * np.exp(1.0)), rel=1e-5)
    assert log_var.grad.item() == pytest.approx(w * 0.5 * (2 - 0.25 * np.exp(1.0)), rel=1e-5)
    assert mean.grad is None or torch.all(mean.grad == 0)
    # Its minimum is where sigma^2 is the mean squared error per channel, whatever beta.
    grid = torch.linspace(-6, 0, 601).view(-1, 1, 1)
    best = grid[beta_nll(mean.detach().expand(601, 2, 1, 1), grid[:, None], truth, 0.0).flatten().argmin()]
    assert float(best) == pytest.approx(np.log(0.125), abs=0.01)


def test_the_spread_is_zero_when_members_agree_and_the_heads_predict_zero():
    means = torch.rand(1, 4, 8, 8).expand(3, 4, 8, 8)
    assert torch.all(total_variance(means, torch.zeros(3, 8, 8)) == 0)
    heads = torch.full((3, 8, 8), 0.01)
    parted = means + torch.randn(3, 1, 8, 8) * 0.1
    assert torch.allclose(total_variance(means, heads), heads[0])
    assert torch.all(total_variance(parted, heads) > 0.01)


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


def test_quadrature_gives_the_mean_and_variance_of_a_whole_image_goal_exactly():
    """A goal the size of the image has one window: eq. (5) is a + 2bz + cz^2 in the shared z,
    whose mean is a + c and variance 4b^2 + 2c^2 (the three points are exact for both)."""
    rng = np.random.default_rng(0)
    image = rng.uniform(0.3, 0.7, (1, 6, 6, 4)).astype(np.float32)
    sigma = rng.uniform(0.0, 0.05, (1, 6, 6)).astype(np.float32)
    goal = Goal(rng.uniform(0.3, 0.7, (6, 6, 4)).astype(np.float32))
    mean, variance = quadrature_losses(goal, image, sigma**2)
    d = image[0] - goal.patch
    a, b, c = (d**2).mean(), (d * sigma[0, ..., None]).mean(), (sigma[0, ..., None] ** 2).mean()
    assert mean[0] == pytest.approx(a + c, rel=1e-4)
    assert variance[0] == pytest.approx(4 * b**2 + 2 * c**2, rel=1e-3)
    assert QUADRATURE[1].sum() == pytest.approx(1.0)
    sure, _ = quadrature_losses(goal, image, np.zeros_like(sigma))
    assert sure[0] == pytest.approx(a, rel=1e-5) and sure[0] < mean[0]


def test_the_head_gives_a_variance_per_pixel_in_range_and_alone_learns():
    torch.manual_seed(0)
    config = with_fields(WITH_HEAD, trained="variance")
    net = PredictionNet(config)
    images, rows = two_outcomes(2), place_rows(2)
    with torch.no_grad():
        log_vars = net.rollout_hypotheses(images[:, 0], rows).log_variance
    assert log_vars.shape == (2, 1, 1, 128, 128)
    lo, hi = LOG_VARIANCE_RANGE
    assert lo <= float(log_vars.min()) and float(log_vars.max()) <= hi
    assert PredictionNet(TINY).rollout_hypotheses(images[:, 0], rows).log_variance is None
    opt = make_optimizer(net, config)
    before = {k: v.clone() for k, v in net.state_dict().items()}
    losses = []
    for _ in range(30):
        loss = sequence_loss(net, images, rows, torch.ones(2, dtype=torch.long))
        opt.zero_grad()
        loss.backward()
        opt.step()
        losses.append(loss.item())
    moved = {k for k, v in net.state_dict().items() if not torch.equal(v, before[k])}
    assert moved and all(k.startswith("decoder.variance") for k in moved)
    assert losses[-1] < losses[0]


def test_a_checkpoint_without_the_head_loads_with_it_and_draws_the_same():
    torch.manual_seed(0)
    old = PredictionNet(TINY)
    net = PredictionNet(WITH_HEAD)
    load_model_state(net, {f"model.{k}": v for k, v in old.state_dict().items()}, "old.safetensors")
    images, rows = two_outcomes(2), place_rows(2)
    with torch.no_grad():
        assert torch.equal(old.rollout(images[:, 0], rows), net.rollout(images[:, 0], rows))
    with pytest.raises(ValueError, match="spatial"):
        PredictionNet(with_fields(PRESETS["tiny-dense"], variance=True))


def test_two_outcomes_each_have_a_variance():
    torch.manual_seed(0)
    net = PredictionNet(with_fields(WITH_HEAD, hypotheses=2, hypotheses_by="effect", fork="latent"))
    images, rows = two_outcomes(2), place_rows(2)
    latent, memory = net.encode(images[:, 0])
    outcomes = net.step_outcomes(latent, memory, images[:, 0], rows[:, 0])
    assert outcomes.log_variance.shape == (2, 2, 1, 128, 128)
    assert torch.all(net.variance(outcomes.log_variance) > 0)


def test_one_net_with_a_variance_head_is_an_ensemble_that_knows_its_spread(scene):
    from test_ensemble import GRASP, SPECS

    from afford.planning.tree import Node
    from afford.planning.uncertain import EnsembleModel
    from afford.recognition.config import PRESETS as REC
    from afford.recognition.infer import Recognizer
    from afford.recognition.model import RecognitionNet

    torch.manual_seed(0)
    net = PredictionNet(WITH_HEAD)
    scene.reset(SPECS)
    recognizer = Recognizer(RecognitionNet(REC["tiny"]), REC["tiny"], 0.0)
    model = EnsembleModel(scene.observe(), recognizer, (net,), 1.0)
    image, state = model.root()
    ((child, child_state),) = model.predict([Node((), image, state)], [GRASP])
    assert child_state.variances.shape == (1, 128, 128) and np.all(child_state.variances > 0)
    node = Node((GRASP,), child, child_state)
    goal = Goal(np.full((8, 8, 4), 0.5, np.float32))
    scores = model.score(goal, [node])
    assert scores.spread[0] > 0 and scores.loss[0] > goal.loss(child[None])[0]


def test_the_variance_calibration_fits_a_scale_on_val(small_dataset):
    from afford.data.format import Dataset
    from afford.prediction.ensemble import calibrate

    torch.manual_seed(0)
    net = PredictionNet(WITH_HEAD)
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
