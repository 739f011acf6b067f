"""Bad starts are refused in one place, the same way from a scene file, a task file and the
Python API: one line naming the file, the object and the field."""

import json
import subprocess
from pathlib import Path

import numpy as np
import pytest
from test_tasks import GOOD

from afford.planning.tasks import TaskError, load_task
from afford.sim.layout import random_layout
from afford.sim.scene import ObjectSpec as O
from afford.sim.scene import SceneError

ROOT = Path(__file__).parents[1]
NAN = float("nan")

# (what is wrong, the objects, what the message must say)
BAD = [
    (
        "a ball off the table",
        [O.upright("ball", 0.60, 0.3)],
        "objects[0] (ball0).pos: x = 0.6 is off the table",
    ),
    (
        "a cup, a ball and the block overlapping",
        [O.upright("cup", 0, 0.3), O.upright("ball", 0, 0.3), O.upright("block", 0, 0.3)],
        "overlaps block0",
    ),
    ("a cup sunk into the table", [O("cup", (0, 0.3, -0.02))], "objects[0] (cup0).pos: sunk"),
    ("a position of 1e9", [O("cup", (1e9, 0.3, 0.04))], "objects[0] (cup0).pos: x = 1e+09 is off the table"),
    (
        "NaN",
        [O.upright("ball", 0.1, 0.3), O("cup", (NAN, 0.3, 0.04))],
        "objects[1] (cup0).pos: expected 3 finite",
    ),
    (
        "4 cups",
        [O.upright("cup", -0.15 + 0.1 * i, 0.3) for i in range(4)],
        "objects[3] (cup3): too many cups",
    ),
    ("a cup floating", [O("cup", (0, 0.3, 0.2))], "objects[0] (cup0).pos: floats"),
    ("a zero quaternion", [O("cup", (0, 0.3, 0.0425), (0, 0, 0, 0))], "objects[0] (cup0).quat"),
    ("a ball high above the table", [O("ball", (0, 0.3, 0.9))], "more than 0.5 m above"),
    ("a ball behind the robot", [O.upright("ball", 0.0, -0.05)], "y = -0.05 is off the table"),
    (
        "two supports in one place",
        [O.upright("support", 0, 0.3), O.upright("support", 0.01, 0.3)],
        "overlaps",
    ),
    ("an unknown kind", [O("plate", (0, 0.3, 0.01))], "objects[0].kind: unknown object kind 'plate'"),
    ("a ball inside the block", [O.upright("block", 0, 0.3), O("ball", (0.05, 0.3, 0.025))], "overlaps"),
    ("a cup on its side, sunk", [O("cup", (0, 0.3, 0.0), (0.7071, 0.7071, 0, 0))], "sunk"),
    (
        "a cup above a ball, not on it",
        [O.upright("ball", 0, 0.3), O.upright("cup", 0, 0.3, z=0.12)],
        "floats",
    ),
]
GOOD_STARTS = [
    [O.upright("block", 0, 0.3), O.upright("cup", 0, 0.3, z=0.05)],  # a cup on the block
    [O.upright("support", 0.1, 0.3), O.upright("ball", 0.1, 0.3, z=0.06)],  # a ball on a support
]


@pytest.mark.parametrize(("what", "objects", "says"), BAD, ids=[b[0] for b in BAD])
def test_python_api_refuses_a_bad_start_with_a_value_error(scene, what, objects, says):
    with pytest.raises(ValueError, match=None) as e:
        scene.reset(objects)
    assert isinstance(e.value, SceneError) and says in str(e.value) and "\n" not in str(e.value)
    assert scene.objects() == []  # refused: an empty table, never a half-built scene


@pytest.mark.parametrize("objects", GOOD_STARTS)
def test_stacked_starts_are_accepted(scene, objects):
    scene.reset(objects)
    assert len(scene.objects()) == len(objects)


def test_random_layouts_pass(scene):
    for seed in range(60):
        scene.reset(random_layout(np.random.default_rng(seed)))  # check on: none may be refused


def _scene_json(objects):
    return {
        "format": 1,
        "objects": [{"kind": o.kind, "pos": list(o.pos), "quat": list(o.quat)} for o in objects],
    }


def test_scene_file_and_task_file_name_the_file_object_and_field(scene, tmp_path, capsys):
    objects = BAD[0][1]
    path = tmp_path / "start.json"
    path.write_text(json.dumps(_scene_json(objects)))
    from afford.cli.main import main

    capsys.readouterr()
    code = main(["scene", "--load", str(path), "--out", str(tmp_path / "a.png")])
    r = subprocess.CompletedProcess([], code, "", capsys.readouterr().err)
    assert r.returncode == 2 and r.stderr.count("\n") == 1
    assert "start.json: objects[0] (ball0).pos: x = 0.6 is off the table" in r.stderr
    task = tmp_path / "task.json"
    sunk = [{"kind": "cup", "pos": [0.0, 0.3, -0.02]}, {"kind": "support", "pos": [0.1, 0.3, 0.03]}]
    task.write_text(json.dumps({**GOOD, "scene": {"objects": sunk}}))
    with pytest.raises(TaskError, match=r"task.json: scene.objects\[0\] \(cup0\).pos: sunk"):
        load_task(task, scene)
