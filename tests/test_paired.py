"""Two nets as one world model (prediction/paired.py): the canonical outcome and head from one,
the side-effect outcome from the other."""

from __future__ import annotations

from dataclasses import asdict

import numpy as np
import pytest
import torch

from afford.prediction.config import PRESETS
from afford.prediction.evaluate import load_net
from afford.prediction.model import PredictionNet
from afford.prediction.paired import SIDE_FILE, PairedNet
from afford.sim.affordance import encode_affordance
from afford.sim.affordances import Affordance
from afford.training.checkpoint import CheckpointError, save_checkpoint
from afford.training.fields import with_fields

BY_EFFECT = with_fields(PRESETS["tiny"], hypotheses=2, hypotheses_by="effect", fork="latent")
TURN = Affordance("turn", (-0.05, 0.22, 0.025), 0.0, False, 90)
GRASP = Affordance("grasp", (0.05, 0.3, 0.0425), 0.0, True)


def _net(seed: int, config=BY_EFFECT) -> PredictionNet:
    torch.manual_seed(seed)
    return PredictionNet(config).eval()


def _inputs(n: int = 3):
    torch.manual_seed(9)
    images = torch.rand(n, 4, 128, 128)
    rows = torch.from_numpy(np.stack([[encode_affordance(a) for a in (TURN, GRASP)]] * n))
    return images, rows


@torch.no_grad()
def test_a_net_paired_with_itself_rolls_out_as_it_does_alone():
    net = _net(0)
    images, rows = _inputs()
    alone = net.rollout_hypotheses(images, rows)
    paired = PairedNet(net, net).rollout_hypotheses(images, rows)
    for name in ("states", "differences", "candidates", "logits", "picks"):
        assert torch.allclose(getattr(alone, name).float(), getattr(paired, name).float(), atol=1e-6)


@torch.no_grad()
def test_each_outcome_is_drawn_by_its_own_net_and_each_net_keeps_its_own_latent():
    main, side = _net(0), _net(1)
    pair = PairedNet(main, side)
    images, rows = _inputs()
    latent, memory = pair.encode(images)
    (lm, mm), (ls, ms) = main.encode(images), side.encode(images)
    assert torch.equal(latent, torch.cat([lm, ls], 1)) and torch.equal(memory, torch.cat([mm, ms], 1))
    out = pair.step_outcomes(latent, memory, images, rows[:, 0])
    own_main = main.step_outcomes(lm, mm, images, rows[:, 0])
    own_side = side.step_outcomes(ls, ms, images, rows[:, 0])
    assert torch.equal(out.images[:, 0], own_main.images[:, 0])  # canonical: the main net's
    assert torch.equal(out.images[:, 1], own_side.images[:, 1])  # side effect: the side net's
    assert torch.equal(out.probability, own_main.probability)  # the main net's head
    c = lm.shape[1]
    for k in range(2):  # outcome k carries each net's own k-th latent
        assert torch.equal(out.latent[:, k, :c], own_main.latent[:, k])
        assert torch.equal(out.latent[:, k, c:], own_side.latent[:, k])
    # Forced to the side effect, the pair's next step starts from the side net's drawing.
    step = pair.step_hypotheses(latent, memory, images, rows[:, 0], label=torch.ones(3))
    assert torch.equal(step.image, own_side.images[:, 1])


def test_nets_that_cannot_pair_say_why(tmp_path):
    with pytest.raises(ValueError, match="hypotheses_by=effect"):
        PairedNet(_net(0), _net(1, PRESETS["tiny"]))
    with pytest.raises(ValueError, match="variance"):
        PairedNet(_net(0), _net(1, with_fields(BY_EFFECT, variance=True)))
    main = tmp_path / "prediction.safetensors"
    save_checkpoint(main, _net(0), "prediction", asdict(BY_EFFECT), 0)
    assert isinstance(load_net(main)[0], PredictionNet)  # alone: no side-effect net beside it
    save_checkpoint(tmp_path / SIDE_FILE, _net(1), "prediction", asdict(BY_EFFECT), 0)
    assert isinstance(load_net(main)[0], PairedNet)
    save_checkpoint(tmp_path / SIDE_FILE, _net(1, PRESETS["tiny"]), "prediction", asdict(PRESETS["tiny"]), 0)
    with pytest.raises(CheckpointError, match="hypotheses_by=effect"):
        load_net(main)


def test_export_ships_a_pair_that_plans(tmp_path, capsys):
    import json

    from afford.cli.main import main
    from afford.recognition.config import PRESETS as REC
    from afford.recognition.model import RecognitionNet
    from afford.shipped import load_learned

    runs = tmp_path / "runs"
    for name, net, config, kind in (
        ("recognition", RecognitionNet(REC["tiny"]), REC["tiny"], "recognition"),
        ("prediction", _net(0), BY_EFFECT, "prediction"),
        ("side", _net(1), BY_EFFECT, "prediction"),
        ("one", _net(2, PRESETS["tiny"]), PRESETS["tiny"], "prediction"),
    ):
        save_checkpoint(runs / name / "best.safetensors", net, kind, asdict(config), 1)
    export = ["export", "--recognition", str(runs / "recognition"), "--prediction", str(runs / "prediction")]
    assert main([*export, "--side", str(runs / "side"), "--out", str(tmp_path / "pair")]) == 0
    assert isinstance(load_learned(tmp_path / "pair").predictor, PairedNet)
    capsys.readouterr()
    task = "tasks/paper/05-counterbalance-cup-first.json"
    plan = ["plan", "--task", task, "--planner", "learned", "--weights", str(tmp_path / "pair"), "--json"]
    code = main([*plan, "--steps", "1", "--out", str(tmp_path / "out")])
    assert code == (0 if json.loads(capsys.readouterr().out)["solved"] else 1)
    # A side-effect net with one outcome cannot pair: one line at export, not at planning.
    assert main([*export, "--side", str(runs / "one"), "--out", str(tmp_path / "bad")]) == 2
    assert "hypotheses_by=effect" in capsys.readouterr().err


def test_a_pair_is_an_ensemble_member_beside_single_nets():
    from afford.planning.tree import Node
    from afford.planning.uncertain import EnsembleModel
    from afford.recognition.config import PRESETS as REC
    from afford.recognition.infer import Recognizer
    from afford.recognition.model import RecognitionNet

    pair, single = PairedNet(_net(0), _net(1)), _net(2)
    images, rows = _inputs(1)
    recognizer = Recognizer(RecognitionNet(REC["tiny"]), REC["tiny"])
    model = EnsembleModel(images[0].permute(1, 2, 0).numpy(), recognizer, (pair, single), 1.0)
    start, state = model.root()
    ((_, child),) = model.predict([Node((), start, state)], [TURN])
    assert child.images.shape == (2, 128, 128, 4)
    assert child.latent[0].shape[0] == 2 * child.latent[1].shape[0]  # the pair's two latents side by side
    with torch.no_grad():
        alone = single.step(state.latent[1][None], state.memory[1][None], images, rows[:, 0])[2]
    assert np.allclose(child.images[1], alone[0].permute(1, 2, 0).numpy(), atol=1e-6)
