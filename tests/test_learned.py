"""The learned world model: latents kept per node equal the chain rerun from the root; CLI plumbing."""

from __future__ import annotations

import json
from dataclasses import asdict
from pathlib import Path

import numpy as np
import pytest
import torch

from afford.cli.main import main
from afford.planning.learned import LearnedModel
from afford.planning.run import PlannerConfig
from afford.planning.tree import Node
from afford.prediction.config import PRESETS as PRED
from afford.prediction.model import PredictionNet
from afford.recognition.config import PRESETS as REC
from afford.recognition.infer import Recognizer
from afford.recognition.model import RecognitionNet
from afford.sim.affordances import Affordance
from afford.sim.scene import ObjectSpec
from afford.training.checkpoint import save_checkpoint

# The paper task `make demo` plans: lay the block across both supports, then place the cup, or
# the block tips (paper IV.C task 3).
DEMO_TASK = "03-stable-base.json"
SPECS = [ObjectSpec.upright("cup", 0.05, 0.3), ObjectSpec.upright("block", -0.05, 0.22)]
PLAN = [
    Affordance("grasp", (0.05, 0.3, 0.0425), 0.0, True),
    Affordance("place", (-0.05, 0.22, 0.05), 90.0, True),
    Affordance("turn", (-0.05, 0.22, 0.025), 0.0, False, 90),
]


def _models(scene):
    torch.manual_seed(0)
    recognizer = Recognizer(RecognitionNet(REC["tiny"]), REC["tiny"])
    predictor = PredictionNet(PRED["tiny"])
    scene.reset(SPECS)
    start = scene.observe()
    keep = LearnedModel(start, recognizer, predictor)
    rerun = LearnedModel(start, recognizer, predictor, rerun_from_root=True)
    return keep, rerun


def test_kept_latents_equal_the_chain_from_the_root(scene):
    keep, rerun = _models(scene)
    chains = []
    for model in (keep, rerun):
        image, state = model.root()
        node = Node((), image, state)
        images = []
        for a in PLAN:
            ((child_image, child_state),) = model.predict([node], [a])
            node = Node(node.plan + (a,), child_image, child_state)
            images.append(child_image)
        chains.append(images)
    for a, b in zip(*chains, strict=True):
        assert np.allclose(a, b, atol=1e-5)
    assert keep.p_steps == 3 and rerun.p_steps == 1 + 2 + 3  # what keeping latents saves


@pytest.mark.slow
def test_plan_with_learned_weights_folder(scene, tmp_path, capsys):
    for kind, net, config in (
        ("recognition", RecognitionNet(REC["tiny"]), REC["tiny"]),
        ("prediction", PredictionNet(PRED["tiny"]), PRED["tiny"]),
    ):
        save_checkpoint(tmp_path / "runs" / kind / "best.safetensors", net, kind, asdict(config), 1)
    runs = tmp_path / "runs"
    weights = tmp_path / "weights"
    for file, run in (("recognition.safetensors", "recognition"), ("prediction.safetensors", "prediction")):
        assert main(["weights", "export", file, "--run", str(runs / run), "--out", str(weights)]) == 0
    capsys.readouterr()
    records = []
    for folder in (runs, weights):
        code = main(
            [
                "plan",
                "--task",
                "tasks/paper/07-sweep.json",
                "--planner",
                "learned",
                "--weights",
                str(folder),
                "--out",
                str(tmp_path / "out"),
                "--json",
            ]
        )
        record = json.loads(capsys.readouterr().out)
        assert code in (0, 1) and record["planner"] == "learned"
        assert Path(record["picture"]).stat().st_size > 1000
        records.append(record)
    # The training runs and the weights exported from them are the same nets: the same tree.
    assert records[0]["plan"] == records[1]["plan"] and records[0]["nodes"] == records[1]["nodes"]
    assert (
        main(
            [
                "plan",
                "--task",
                "tasks/paper/07-sweep.json",
                "--planner",
                "learned",
                "--weights",
                str(tmp_path / "nothing"),
            ]
        )
        == 2
    )
    assert "no recognition.safetensors" in capsys.readouterr().err


@pytest.mark.slow
def test_shipped_weights_plan_a_paper_task_that_needs_a_non_canonical_effect(scene):
    """End to end, the paper's method: recognise on the real image, predict, recognise on the
    predicted images, match the goal, execute the plan in the simulator, judge it."""
    from afford.planning.run import solve
    from afford.planning.tasks import load_task
    from afford.planning.tree import SearchConfig
    from afford.shipped import Nets

    torch.set_num_threads(2)
    task = load_task(Path(__file__).parents[1] / "tasks" / "paper" / DEMO_TASK, scene)
    o = solve(task, "learned", scene, PlannerConfig(search=SearchConfig(progress=False)), Nets())
    assert o.success, o.reason


def test_diagnosis_names_recognition_when_the_working_plan_is_not_recognised(scene):
    """Untrained nets recognise nothing confidently: the oracle's grasp-and-place is not in the
    learned tree, so the failure is recognition's."""
    from helpers import GOOD

    from afford.planning.diagnose import diagnose
    from afford.planning.tasks import task_from_json
    from afford.shipped import Nets

    torch.manual_seed(0)
    recognizer = Recognizer(RecognitionNet(REC["tiny"]), REC["tiny"], threshold=0.999)
    task = task_from_json(GOOD, scene=scene)
    d = diagnose(task, scene, Nets(recognizer=recognizer, predictor=PredictionNet(PRED["tiny"])))
    assert d.oracle.success and not d.learned.success
    assert d.cause == "recognition"
    assert [s.action for s in d.steps] == ["grasp", "place"] and not d.steps[0].recognised
    assert d.steps[-1].true_loss < 1e-3  # the oracle's plan truly reaches the goal image
    assert "NOT recognised" in d.describe() and d.to_dict()["cause"] == "recognition"
