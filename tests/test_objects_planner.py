"""The object world model in the planner, with the shipped nets: a two-step plan, closed loop
and the plan report."""

from __future__ import annotations

import json

import numpy as np

from afford.cli.main import main
from afford.planning.objects_model import ObjectsBranchingModel, ObjectsModel
from afford.planning.run import solve
from afford.planning.strategies import search
from afford.planning.tasks import load_task
from afford.planning.tree import SearchConfig
from afford.shipped import Nets

TASK = "tasks/examples/cup-on-block.json"  # a cup onto the block: grasp, then place
NETS = Nets()  # the package's nets, each loaded once for the module's tests


def test_a_two_step_plan_is_found_and_its_states_are_drawn(scene):
    task = load_task(TASK)
    scene.reset(task.scene)
    start = scene.observe()
    model = ObjectsModel(start, NETS.recognizer, NETS.perception, NETS.dynamics, NETS.drawer)
    result = search(model, task.goal, 2, SearchConfig())
    assert [a.type for a in result.plan] == ["grasp", "place"]
    chosen = result.path()
    # eq. (3): the grasp changes the cup and the gripper, and copies every other pixel exactly
    changed = np.abs(chosen[1].image - start).max(-1) > 0
    assert 0 < changed.mean() < 0.1
    assert len({id(n.state) for n in result.nodes}) == len(result.nodes)


def test_the_true_start_is_the_simulators_objects_and_plans_the_task(scene):
    from afford.data.draws import pose_array
    from afford.objects.world import given

    task = load_task(TASK)
    scene.reset(task.scene)
    poses, mask = pose_array(scene), scene.instance_mask()
    nets = (NETS.recognizer, NETS.perception, NETS.dynamics, NETS.drawer)
    model = ObjectsModel(scene.observe(), *nets, start=given(NETS.drawer, poses, -1, mask))
    _, state = model.root()
    np.testing.assert_array_equal(state.poses, poses)
    assert state.held == -1 and state.seen.shape[0] == len(poses)
    np.testing.assert_array_equal(state.seen.any(0), mask >= 0)
    outcome = solve(task, "objects-true", scene)
    assert outcome.success and [a.type for a in outcome.plan] == ["grasp", "place"]


def test_every_outcome_kept_as_a_branch_still_finds_the_plan(scene):
    task = load_task(TASK)
    scene.reset(task.scene)
    nets = (NETS.recognizer, NETS.perception, NETS.dynamics, NETS.drawer)
    model = ObjectsBranchingModel(scene.observe(), *nets, risk=0.5)
    result = search(model, task.goal, 2, SearchConfig())
    assert [a.type for a in result.plan] == ["grasp", "place"]
    assert max(len(n.state.branches) for n in result.nodes) > 1  # the dynamics foresaw alternatives
    for node in result.nodes:
        branches = node.state
        assert np.isclose(branches.probability.sum(), 1.0) and len(branches.branches) == len(branches.images)
        assert np.all(np.diff(branches.probability) <= 1e-9)  # likeliest first
        np.testing.assert_array_equal(node.image, branches.images[0])


def test_plan_closed_loop_with_a_report(tmp_path, capsys):
    report = tmp_path / "plan.html"
    code = main(
        [
            "plan",
            "--task",
            TASK,
            "--planner",
            "objects",
            "--closed-loop",
            "--report",
            str(report),
            "--out",
            str(tmp_path / "out"),
            "--json",
        ]
    )
    record = json.loads(capsys.readouterr().out)
    assert code == 0 and record["solved"], record
    assert report.is_file() and report.stat().st_size > 10_000


def test_a_weights_folder_gives_every_net_from_itself_and_names_the_one_it_lacks(tmp_path, capsys):
    import shutil

    from afford.shipped import DYNAMICS_FILE, OBJECTS, RECOGNITION_FILE, WEIGHTS

    (tmp_path / "objects").mkdir()
    shutil.copy(WEIGHTS / RECOGNITION_FILE, tmp_path / RECOGNITION_FILE)
    shutil.copy(OBJECTS / DYNAMICS_FILE, tmp_path / "objects" / DYNAMICS_FILE)
    nets = Nets(tmp_path)
    assert nets.dynamics is not None and nets.recognizer is not None
    # the perception net it lacks is not taken from the package: the planner says so in one line
    code = main(["plan", "--task", TASK, "--planner", "objects", "--weights", str(tmp_path)])
    err = capsys.readouterr().err.strip()
    assert code == 2 and len(err.splitlines()) == 1 and "objects/perception.safetensors" in err, err


def test_canonical_plans_checked_by_the_object_world_model(tmp_path, capsys, scene):
    for extra in ([], ["--closed-loop"]):
        out = ["--out", str(tmp_path / "out")]
        code = main(["plan", "--task", TASK, "--planner", "hybrid-objects", "--json", *out, *extra])
        record = json.loads(capsys.readouterr().out)
        assert code == 0 and record["solved"] and record["planner"] == "hybrid-objects", record
    # open loop, the object world model kept a canonical plan (it did not fall back to search)
    outcome = solve(load_task(TASK, scene), "hybrid-objects", scene)
    assert outcome.source == "symbolic" and outcome.success


def test_a_failure_is_diagnosed_through_the_object_world_model(scene):
    """With a recognition net that recognises nothing, the oracle's plan is replayed through the
    object world model's drawn states and the failure named recognition's."""
    import torch
    from helpers import GOOD

    from afford.planning.diagnose import diagnose
    from afford.planning.tasks import task_from_json
    from afford.prediction.config import PRESETS as PRED
    from afford.prediction.model import PredictionNet
    from afford.recognition.config import PRESETS as REC
    from afford.recognition.infer import Recognizer
    from afford.recognition.model import RecognitionNet

    torch.manual_seed(0)
    recognizer = Recognizer(RecognitionNet(REC["tiny"]), REC["tiny"], threshold=0.999)
    task = task_from_json(GOOD, scene=scene)
    d = diagnose(
        task, scene, Nets(recognizer=recognizer, predictor=PredictionNet(PRED["tiny"])), planner="objects"
    )
    assert d.oracle.success and not d.learned.success
    assert d.cause == "recognition" and d.to_dict()["planner"] == "objects"
    assert d.steps[-1].true_loss < 1e-3


def test_outcomes_alike_are_one_branch_drawn_from_the_likeliest():
    from afford.objects.dynamics import ObjectOutcomes
    from afford.planning.objects_model import _distinct

    upright = [0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0]
    poses = np.full((3, 2, 2, 7), np.nan, dtype=np.float32)  # (rows, K, slots, 7)
    poses[:, :, 0] = upright
    poses[0, 1, 0, 0] = 0.05  # row 0's second outcome moves the object 5 cm
    poses[1, 0, 0, 0] = 0.0005  # row 1's first is row 0's first, half a millimetre off
    poses[1, 1, 0, 0] = 0.05
    poses[2, 0, 0, 3:7] = [0.0, 0.0, 0.0, 1.0]  # row 2 (another parent): the object turned
    outcomes = ObjectOutcomes(poses, np.full((3, 2), -1), np.array([[0.9, 0.1], [0.3, 0.7], [0.5, 0.5]]))
    found = _distinct(outcomes, range(0, 2), np.array([0.4, 0.6]))
    # 0.4 * 0.9 + 0.6 * 0.3 stay, 0.4 * 0.1 + 0.6 * 0.7 move; each drawn from its likeliest
    assert np.allclose([f.probability for f in found], [0.54, 0.46])
    assert [(f.row, f.outcome) for f in found] == [(0, 0), (1, 1)]
    found = _distinct(outcomes, range(0, 3), np.array([0.2, 0.3, 0.5]))
    assert len(found) == 3 and np.isclose(sum(f.probability for f in found), 1.0)


def test_the_planner_and_the_rollout_take_the_same_object_step(scene):
    """One step of the object world model (`objects/world.step`): the planner's child of an
    action is the rollout's first predicted image of it, to the pixel."""
    import torch

    from afford.images import to_chw, to_hwc
    from afford.objects.rollout import ObjectRollout
    from afford.planning.tree import Node
    from afford.sim.affordance import encode_affordance

    task = load_task(TASK)
    scene.reset(task.scene)
    image = scene.observe()
    action = next(a for a in scene.affordances() if a.type == "grasp")
    model = ObjectsModel(image, NETS.recognizer, NETS.perception, NETS.dynamics, NETS.drawer)
    start, state = model.root()
    ((child, _),) = model.predict([Node((), start, state)], [action])
    rows = torch.from_numpy(encode_affordance(action)[None, None])
    rolled = ObjectRollout(NETS.perception, NETS.dynamics, NETS.drawer).rollout(to_chw(image[None]), rows)
    np.testing.assert_array_equal(to_hwc(rolled[:, 0])[0], child)


def test_the_true_start_plans_again_from_the_objects_as_they_are(scene):
    """objects-true in closed loop: each round starts from the simulator's objects as the
    last action left them, the gripper's held object among them."""
    from afford.planning.outcome import PlannerConfig

    task = load_task(TASK)
    config = PlannerConfig(search=SearchConfig(progress=False), closed_loop=True)
    outcome = solve(task, "objects-true", scene, config, NETS)
    assert outcome.success and [a.type for a in outcome.plan] == ["grasp", "place"]
    assert len(outcome.loop.steps) == 2
