"""The object world model in the planner, with the shipped nets: a two-step plan, closed loop
and the plan report."""

from __future__ import annotations

import json

import numpy as np

from afford.cli.main import main
from afford.objects.draw import Drawer
from afford.planning.objects_model import ObjectsModel
from afford.planning.strategies import search
from afford.planning.tasks import load_task
from afford.planning.tree import SearchConfig
from afford.shipped import load_learned, load_object_dynamics, load_object_perception

TASK = "tasks/examples/cup-on-block.json"  # a cup onto the block: grasp, then place


def test_a_two_step_plan_is_found_and_its_states_are_drawn(scene):
    task = load_task(TASK)
    scene.reset(task.scene)
    start = scene.observe()
    model = ObjectsModel(
        start, load_learned().recognizer, load_object_perception(), load_object_dynamics(), Drawer()
    )
    result = search(model, task.goal, 2, SearchConfig())
    assert [a.type for a in result.plan] == ["grasp", "place"]
    chosen = result.path()
    # eq. (3): the grasp changes the cup and the gripper, and copies every other pixel exactly
    changed = np.abs(chosen[1].image - start).max(-1) > 0
    assert 0 < changed.mean() < 0.1
    assert len({id(n.state) for n in result.nodes}) == len(result.nodes)


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
