"""Perturbed executions (sim/perturb.py, `--perturb`/`--executions`): each pile of objects
shifted and turned as one, the draws seeded, and the plan's success counted per execution."""

from __future__ import annotations

import json
from dataclasses import asdict

import numpy as np
import pytest
import torch

from afford.cli.main import main
from afford.prediction.config import PRESETS as PRED
from afford.prediction.model import PredictionNet
from afford.recognition.config import PRESETS as REC
from afford.recognition.model import RecognitionNet
from afford.sim.perturb import Perturbation, piles, reset_perturbed
from afford.sim.scene import ObjectSpec

# A pile: the cup on the block on a support, and a ball on its own.
PILE = [
    ObjectSpec.upright("support", 0.0, 0.3),
    ObjectSpec.upright("block", 0.0, 0.3, z=0.06),
    ObjectSpec.upright("cup", 0.0, 0.3, z=0.11),
    ObjectSpec.upright("ball", -0.15, 0.2),
]
TASK = "tasks/uncertain/01-cup-near-a-tipping-edge.json"


def test_a_pile_is_perturbed_as_one_and_the_draws_are_seeded(scene):
    assert piles(scene, PILE) == [0, 0, 0, 3]
    big = Perturbation(position=0.01, yaw=5.0)
    a = big.draw(PILE, [0, 0, 0, 3], np.random.default_rng(1))
    b = big.draw(PILE, [0, 0, 0, 3], np.random.default_rng(1))
    assert a == b
    moved = np.array(a[0].pos) - np.array(PILE[0].pos)
    assert np.linalg.norm(moved[:2]) > 1e-4 and moved[2] == 0.0  # shifted on the table, not lifted
    for i in (1, 2):  # what rests on the support keeps its place on it (centred piles)
        assert np.allclose(np.array(a[i].pos[:2]) - np.array(a[0].pos[:2]), 0.0, atol=1e-9)
    assert not np.allclose(a[3].pos, PILE[3].pos)  # the ball has its own draw
    none = Perturbation(0.0, 0.0).draw(PILE, [0, 0, 0, 3], np.random.default_rng(1))
    assert [s.pos for s in none] == [s.pos for s in PILE]


def test_a_perturbed_start_is_a_valid_settled_scene(scene):
    drawn = reset_perturbed(scene, PILE, Perturbation(0.005, 3.0), np.random.default_rng(2))
    cup = scene.object("cup0")
    assert cup.present and np.linalg.norm(cup.pos[:2] - np.array(drawn[2].pos[:2])) < 0.005
    with pytest.raises(ValueError, match=">= 0"):
        Perturbation(-0.01)


def test_a_bad_perturb_is_a_one_line_error(tmp_path, capsys):
    assert main(["plan", "--task", TASK, "--perturb", "a,b", "--out", str(tmp_path)]) == 2
    assert "--perturb 'a,b'" in capsys.readouterr().err
    assert (
        main(["plan", "--task", TASK, "--perturb", "0.005", "--executions", "0", "--out", str(tmp_path)]) == 2
    )
    assert "--executions" in capsys.readouterr().err


def test_the_learned_plan_is_executed_from_perturbed_starts_and_its_record_counts_them(tmp_path, capsys):
    from afford.training.checkpoint import save_checkpoint

    torch.manual_seed(0)
    runs, weights = tmp_path / "runs", tmp_path / "weights"
    for name, net, config in (
        ("recognition", RecognitionNet(REC["tiny"]), REC["tiny"]),
        ("prediction", PredictionNet(PRED["tiny"]), PRED["tiny"]),
    ):
        save_checkpoint(runs / name / "best.safetensors", net, name, asdict(config), 1)
        file = f"{name}.safetensors"
        assert main(["weights", "export", file, "--run", str(runs / name), "--out", str(weights)]) == 0
    capsys.readouterr()
    plan = ["plan", "--task", TASK, "--planner", "learned", "--weights", str(weights)]
    code = main([*plan, "--perturb", "0.005", "--executions", "2", "--out", str(tmp_path / "out"), "--json"])
    record = json.loads(capsys.readouterr().out)
    assert code == (0 if record["solved"] else 1) and record["planner"] == "learned"
    assert record["perturbed_executions"] == 2 and record["perturbed_success_rate"] in (0, 0.5, 1)
