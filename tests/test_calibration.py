"""The choice head's calibration (prediction/calibration.py): Platt scaling, applied by the net."""

from __future__ import annotations

from dataclasses import asdict

import numpy as np
import torch

from afford.prediction.calibration import fit_platt, report
from afford.prediction.config import PRESETS, PredictionConfig
from afford.prediction.evaluate import load_net
from afford.prediction.model import PredictionNet
from afford.training.checkpoint import export_weights, save_checkpoint
from afford.training.fields import with_fields

EFFECT = with_fields(PRESETS["tiny"], hypotheses=2, hypotheses_by="effect", fork="latent")


def test_platt_scaling_recovers_the_scale_and_bias_the_labels_were_drawn_with():
    rng = np.random.default_rng(0)
    z = rng.normal(0, 2, 20_000)
    labels = rng.random(len(z)) < 1 / (1 + np.exp(-(0.6 * z - 1.5)))
    scale, bias = fit_platt(z, labels)
    assert abs(scale - 0.6) < 0.05 and abs(bias + 1.5) < 0.08
    r = report(z, labels, scale, bias)
    assert abs(r.mean_calibrated - r.rate) < 0.01 and r.nll_calibrated < r.nll_raw


def test_the_net_reads_its_head_through_the_calibration_and_export_keeps_it(tmp_path):
    logits = torch.tensor([[0.0, 2.0], [1.0, -1.0]])
    net = PredictionNet(with_fields(EFFECT, choice_scale=0.5, choice_bias=-1.0))
    side = net.probabilities(logits)[:, 1]
    assert torch.allclose(side, torch.sigmoid(torch.tensor([0.0, -2.0])))
    assert torch.allclose(net.probabilities(logits).sum(1), torch.ones(2))
    plain = PredictionNet(EFFECT)
    assert torch.allclose(plain.probabilities(logits), logits.softmax(1))  # uncalibrated: the softmax
    save_checkpoint(tmp_path / "run" / "best.safetensors", plain, "prediction", asdict(EFFECT), 1)
    export_weights(
        tmp_path / "run" / "best.safetensors",
        tmp_path / "w.safetensors",
        "prediction",
        config={"choice_scale": 0.5, "choice_bias": -1.0},
        config_cls=PredictionConfig,
    )
    _, config = load_net(tmp_path / "w.safetensors")
    assert (config.outcomes.choice_scale, config.outcomes.choice_bias) == (0.5, -1.0)


def test_eval_draws_each_outcome_forced_beside_the_heads_pick(tmp_path, small_dataset):
    from afford.prediction.evaluate import evaluate, forced, format_table

    torch.manual_seed(0)
    net = PredictionNet(EFFECT).eval()
    images, actions = torch.rand(2, 4, 128, 128), torch.zeros(2, 2, 7)
    candidates = net.rollout_hypotheses(images, actions).candidates
    for k in range(2):
        assert torch.equal(forced(net, k, images, actions), candidates[:, :, k])
    save_checkpoint(tmp_path / "run" / "best.safetensors", net, "prediction", asdict(EFFECT), 1)
    result = evaluate(tmp_path / "run" / "best.safetensors", small_dataset)
    assert len(result["foresight_forced"]) == 2
    assert (
        result["foresight_forced"][0]["acted"]["all"]["executions"]
        == result["foresight"]["acted"]["all"]["executions"]
    )
    assert "outcome 2 drawn at every step" in format_table(result)


def test_the_head_is_read_through_its_action_types_own_scaling_where_the_config_has_one():
    from afford.prediction.calibration import fit_per_type, per_type_logits

    rng = np.random.default_rng(1)
    z = rng.normal(0, 2, 30_000)
    kinds = rng.integers(0, 3, len(z))
    truth = (np.array([0.5, 1.0, 0.8]), np.array([-2.0, -0.5, 0.3]))
    labels = rng.random(len(z)) < 1 / (1 + np.exp(-per_type_logits(z, kinds, *truth)))
    scales, biases = fit_per_type(z, labels, kinds)
    assert np.allclose(scales, truth[0], atol=0.1) and np.allclose(biases, truth[1], atol=0.12)
    net = PredictionNet(with_fields(EFFECT, choice_scales=tuple(scales), choice_biases=tuple(biases)))
    logits = torch.tensor([[0.0, 1.0], [0.0, 1.0], [0.0, 1.0]])
    rows = torch.zeros(3, 7)
    rows[:, 0] = torch.tensor([0.0, 1.0, 2.0])  # a grasp, a place, a turn
    side = net.probabilities(logits, rows)[:, 1]
    assert torch.allclose(side, torch.sigmoid(torch.tensor(scales) + torch.tensor(biases)), atol=1e-6)
    assert torch.allclose(
        net.probabilities(logits)[:, 1], torch.sigmoid(torch.tensor(1.0))
    )  # no rows: one for all
