"""Uncertain outcomes (paper V): the ensemble's spread, risk-averse scores, perturbed executions."""

from __future__ import annotations

import copy
import json

import numpy as np
import pytest
import torch

from afford.cli.main import main
from afford.data.format import Dataset
from afford.planning.goal import Goal
from afford.planning.run import PlannerConfig
from afford.planning.strategies import search
from afford.planning.tree import Node, SearchConfig
from afford.planning.uncertain import EnsembleError, EnsembleModel, risk_score
from afford.prediction.config import PRESETS as PRED
from afford.prediction.ensemble import calibrate, spread
from afford.prediction.model import PredictionNet
from afford.recognition.config import PRESETS as REC
from afford.recognition.infer import Recognizer
from afford.recognition.model import RecognitionNet
from afford.sim.affordances import Affordance
from afford.sim.perturb import Perturbation, piles, reset_perturbed
from afford.sim.scene import ObjectSpec

SPECS = [ObjectSpec.upright("cup", 0.05, 0.3), ObjectSpec.upright("block", -0.05, 0.22)]
GRASP = Affordance("grasp", (0.05, 0.3, 0.0425), 0.0, True)
# A pile: the cup on the block on a support, and a ball on its own.
PILE = [
    ObjectSpec.upright("support", 0.0, 0.3),
    ObjectSpec.upright("block", 0.0, 0.3, z=0.06),
    ObjectSpec.upright("cup", 0.0, 0.3, z=0.11),
    ObjectSpec.upright("ball", -0.15, 0.2),
]


def _nets(k: int, same: bool):
    torch.manual_seed(0)
    first = PredictionNet(PRED["tiny"])
    members = [first]
    for seed in range(1, k):
        if same:
            members.append(copy.deepcopy(first))
        else:
            torch.manual_seed(seed)
            members.append(PredictionNet(PRED["tiny"]))
    recognizer = Recognizer(RecognitionNet(REC["tiny"]), REC["tiny"], threshold=0.0)
    return recognizer, tuple(members)


def _predicted(scene, same: bool):
    recognizer, members = _nets(3, same)
    scene.reset(SPECS)
    model = EnsembleModel(scene.observe(), recognizer, members, risk=1.0)
    image, state = model.root()
    ((child, child_state),) = model.predict([Node((), image, state)], [GRASP])
    return model, Node((GRASP,), child, child_state)


def test_the_spread_is_zero_when_the_members_agree(scene):
    model, node = _predicted(scene, same=True)
    assert np.allclose(node.state.pixel_spread, 0.0, atol=1e-6)
    goal = Goal(np.full((8, 8, 4), 0.5, np.float32))
    scores = model.score(goal, [node])
    assert scores.spread[0] == pytest.approx(0.0, abs=1e-7)
    plain = goal.loss(node.image[None])[0]
    assert scores.loss[0] == pytest.approx(plain, rel=1e-5)  # the mean: nothing added


def test_members_that_differ_spread_and_their_mean_is_the_node_image(scene):
    model, node = _predicted(scene, same=False)
    assert node.state.pixel_spread.max() > 1e-3
    assert np.allclose(node.image, node.state.images.mean(axis=0), atol=1e-6)
    assert np.allclose(spread(node.state.images), node.state.images.std(axis=0).mean(axis=-1))


def test_risk_prefers_the_outcome_the_members_agree_on():
    # Two plans, each scored by 3 members: the same mean loss, one of them spread out.
    losses = np.array([[0.10, 0.02], [0.10, 0.10], [0.10, 0.18]])
    averse, spreads = risk_score(losses, risk=1.0, negative=False)
    assert np.argmin(averse) == 0 and spreads[0] == pytest.approx(0.0, abs=1e-12) and spreads[1] > 0.06
    plain, _ = risk_score(losses, risk=0.0, negative=False)
    assert np.allclose(plain, 0.10)
    # A negative goal keeps the largest loss: the spread counts against that instead.
    negative, _ = risk_score(losses, risk=1.0, negative=True)
    assert np.argmax(negative) == 0


@pytest.mark.slow
def test_the_ensemble_search_scores_every_state_and_needs_two_members(scene):
    recognizer, members = _nets(2, same=False)
    scene.reset(SPECS)
    start = scene.observe()
    goal = Goal(start[40:60, 40:60])
    result = search(
        EnsembleModel(start, recognizer, members, 1.0), goal, 1, SearchConfig(progress=False, budget=12)
    )
    assert len(result.nodes) > 1 and all(np.isfinite(n.loss) for n in result.nodes)
    assert result.nodes[0].spread == pytest.approx(0.0, abs=1e-9)  # every member starts from the real image
    assert all(n.spread > 0 for n in result.nodes[1:])  # untrained members part at once
    with pytest.raises(EnsembleError, match="at least 2"):
        EnsembleModel(start, recognizer, members[:1], 1.0)


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


def test_calibration_has_one_spread_and_error_per_predicted_state(small_dataset):
    _, members = _nets(2, same=False)
    cal = calibrate(members, Dataset(small_dataset), "train", batch=4)
    assert len(cal.spread) == len(cal.error) == len(cal.step) > 0
    assert np.all(cal.spread > 0) and np.all(cal.error >= 0)
    assert -1.0 <= cal.rank_correlation() <= 1.0
    assert sum(b["states"] for b in cal.by_spread(2)) == len(cal.spread)


def test_bad_perturb_and_missing_members_are_one_line_errors(tmp_path, capsys):
    task = "tasks/uncertain/01-cup-near-a-tipping-edge.json"
    assert main(["plan", "--task", task, "--perturb", "a,b", "--out", str(tmp_path)]) == 2
    assert "--perturb 'a,b'" in capsys.readouterr().err
    assert (
        main(["plan", "--task", task, "--perturb", "0.005", "--executions", "0", "--out", str(tmp_path)]) == 2
    )
    assert "--executions" in capsys.readouterr().err


def test_exported_members_make_the_ensemble_planner_and_its_record(tmp_path, capsys):
    from dataclasses import asdict

    from afford.shipped import Nets
    from afford.training.checkpoint import save_checkpoint

    torch.manual_seed(0)
    runs = tmp_path / "runs"
    for name, net, config, kind in (
        ("recognition", RecognitionNet(REC["tiny"]), REC["tiny"], "recognition"),
        ("prediction", PredictionNet(PRED["tiny"]), PRED["tiny"], "prediction"),
        ("member", PredictionNet(PRED["tiny"]), PRED["tiny"], "prediction"),
    ):
        save_checkpoint(runs / name / "best.safetensors", net, kind, asdict(config), 1)
    # A member's head calibration goes into its config, as the main prediction net's does.
    (runs / "member" / "calibration.json").write_text(json.dumps({"choice_scale": 0.5, "choice_bias": -1.0}))
    for out in ("alone", "two"):
        for file, run in (
            ("recognition.safetensors", "recognition"),
            ("prediction.safetensors", "prediction"),
        ):
            assert (
                main(["weights", "export", file, "--run", str(runs / run), "--out", str(tmp_path / out)]) == 0
            )
    member = ["weights", "export", "ensemble/prediction-1.safetensors", "--run", str(runs / "member")]
    assert main([*member, "--out", str(tmp_path / "two")]) == 0
    members = Nets(tmp_path / "two").members
    head = (members[1].config.outcomes.choice_scale, members[1].config.outcomes.choice_bias)
    assert len(members) == 2 and head == (0.5, -1.0)
    capsys.readouterr()
    task = "tasks/uncertain/01-cup-near-a-tipping-edge.json"
    plan = ["plan", "--task", task, "--planner", "ensemble", "--out", str(tmp_path / "out")]
    assert main([*plan, "--weights", str(tmp_path / "alone")]) == 2
    assert "ensemble/" in capsys.readouterr().err
    code = main(
        [*plan, "--weights", str(tmp_path / "two"), "--perturb", "0.005", "--executions", "2", "--json"]
    )
    record = json.loads(capsys.readouterr().out)
    # Two untrained members that differ: every state they predict has a spread; the start,
    # which both see as it is, has none.
    assert code == (0 if record["solved"] else 1) and record["planner"] == "ensemble"
    assert record["spread"] == 0 if record["plan_length"] == 0 else record["spread"] > 0
    assert record["perturbed_executions"] == 2 and record["perturbed_success_rate"] in (0, 0.5, 1)


def test_the_tipping_edge_task_holds_unperturbed_and_tips_when_the_pile_shifts(scene):
    """The premise of tasks/uncertain/01: the cup placed at the block's right end stays up as
    planned, but lands too far out when the pile stands 6 mm left of where the plan aimed: the
    block tips under it and throws it off (the task's success check fails)."""
    from afford.planning.tasks import load_task
    from afford.sim.resting import rests_on

    task = load_task("tasks/uncertain/01-cup-near-a-tipping-edge.json", scene)
    scene.reset(task.scene)
    grasp = next(a for a in scene.affordances() if a.type == "grasp")
    scene.execute(grasp)
    end = next(a for a in scene.affordances() if a.type == "place" and a.position[0] > 0.08)
    shifted = [
        s if s.kind == "cup" else ObjectSpec(s.kind, (s.pos[0] - 0.006, *s.pos[1:]), s.quat)
        for s in task.scene
    ]
    for start, holds in ((task.scene, True), (shifted, False)):
        scene.reset(start)
        assert scene.execute(grasp).executed and scene.execute(end).executed
        assert (rests_on(scene, "cup0", "block0") and rests_on(scene, "block0", "support0")) == holds


@pytest.mark.slow
@pytest.mark.xfail(
    strict=True,
    reason="the shipped ensemble's members learned the world whose supports were posts alone: on "
    "the footed world they find no plan for tasks/uncertain/02 (its statics hold: the test above "
    "and `afford bench tasks --planner oracle --tasks tasks/uncertain`)",
)
def test_the_shipped_ensemble_plans_a_tipping_edge_task_and_sees_its_spread(scene):
    from afford.planning.run import solve
    from afford.planning.tasks import load_task
    from afford.shipped import Nets

    nets = Nets()
    assert len(nets.members) == 3 and nets.members[0] is nets.predictor
    task = load_task("tasks/uncertain/02-ball-near-a-tipping-edge.json", scene)
    o = solve(task, "ensemble", scene, PlannerConfig(search=SearchConfig(progress=False)), nets)
    # Members trained apart part at the tipping end, so the risk-averse plan places the ball at
    # the block's centre (the block lies at x = 0), where it holds however the pile stands.
    assert o.success and o.plan[-1].type == "place" and abs(o.plan[-1].position[0]) < 0.03
    assert 0 < o.spread < o.loss
