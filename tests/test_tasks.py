"""Task files: the paper's ten load; every mistake is one error naming its field."""

import copy
import json
from pathlib import Path

import numpy as np
import pytest
from helpers import GOOD

from afford.planning.predicates import PredicateError, parse
from afford.planning.tasks import TaskError, load_task, save_goal_png, task_from_json
from afford.sim.scene import ObjectSpec

PAPER = sorted(Path(__file__).parents[1].joinpath("tasks", "paper").glob("*.json"))


def test_the_ten_paper_tasks_load(scene):
    assert len(PAPER) == 10
    for f in PAPER:
        task = load_task(f, scene)
        assert task.challenge and 1 <= task.max_steps <= 4
        assert task.goal.negative == (task.goal.channels == "rgb")  # the paper drops depth for NOT goals


def test_a_good_task_renders_its_goal(scene):
    task = task_from_json(GOOD, scene=scene)
    assert task.goal.patch.shape == (16, 16, 4)
    assert task.object_names() == ["cup0", "support0"]
    assert task.success.describe() == "cup0 on support0"


@pytest.mark.parametrize(
    "edit, field",
    [
        (lambda t: t.pop("goal"), "'goal'"),
        (lambda t: t.update(max_steps=0), "max_steps"),
        (lambda t: t.update(extra=1), "'extra'"),
        (lambda t: t["goal"].update(type="maybe"), "goal.type"),
        (lambda t: t["goal"].update(channels="depth"), "goal.channels"),
        (lambda t: t["goal"].update(crop=[120, 120, 16, 16]), "goal.crop"),
        (lambda t: t["goal"].update(image="x.png"), "goal"),
        (lambda t: t["scene"]["objects"][0].update(kind="mug"), "scene.objects[0].kind"),
        (lambda t: t["scene"]["objects"][1].update(pos=[0, 1]), "scene.objects[1].pos"),
        (lambda t: t.update(success={"on": {"object": "cup3", "host": "support0"}}), "success.on.object"),
        (lambda t: t.update(success={"on": {"object": "cup0", "host": "cup0"}}), "success.on.host"),
        (lambda t: t.update(success={"near": {"object": "cup0", "to": [0, 0]}}), "success.near.to"),
        (lambda t: t.update(success={"fly": "cup0"}), "unknown predicate"),
        (lambda t: t.update(success={"all": []}), "success.all"),
    ],
)
def test_bad_tasks_name_the_field(scene, edit, field):
    bad = copy.deepcopy(GOOD)
    edit(bad)
    with pytest.raises((TaskError, PredicateError, ValueError)) as e:
        task_from_json(bad, scene=scene)
    assert field in str(e.value)
    assert "\n" not in str(e.value)


def test_goal_image_files_round_trip(tmp_path, scene):
    rng = np.random.default_rng(0)
    patch = rng.random((10, 12, 4)).astype(np.float32)
    save_goal_png(patch, tmp_path / "goal.png")
    np.save(tmp_path / "goal.npy", patch[..., :3])
    for name, channels, shape in (("goal.png", "rgbd", (10, 12, 4)), ("goal.npy", "rgb", (10, 12, 3))):
        t = copy.deepcopy(GOOD)
        t["goal"] = {"type": "positive", "image": name, "channels": channels}
        (tmp_path / "t.json").write_text(json.dumps(t))
        task = load_task(tmp_path / "t.json", scene)
        assert task.goal.patch.shape == shape
        np.testing.assert_allclose(task.goal.patch, patch[..., : shape[2]], atol=1 / 255)
    t["goal"] = {"type": "positive", "image": "goal.npy", "channels": "rgbd"}
    (tmp_path / "t.json").write_text(json.dumps(t))
    with pytest.raises(TaskError, match="no depth channel"):
        load_task(tmp_path / "t.json", scene)


def test_missing_and_corrupt_files(tmp_path):
    with pytest.raises(TaskError, match="no such task file"):
        load_task(tmp_path / "nope.json")
    (tmp_path / "bad.json").write_text("{ not json")
    with pytest.raises(TaskError, match="not valid JSON"):
        load_task(tmp_path / "bad.json")


def test_predicates_on_true_poses(scene):
    names = {"cup0", "ball0", "support0"}
    scene.reset(
        [
            ObjectSpec.upright("cup", 0.1, 0.3, z=0.06),
            ObjectSpec.upright("ball", -0.1, 0.3),
            ObjectSpec.upright("support", 0.1, 0.3),
        ]
    )
    assert parse({"on": {"object": "cup0", "host": "support0"}}, names).holds(scene)
    assert not parse({"on": {"object": "ball0", "host": "support0"}}, names).holds(scene)
    assert parse({"on": {"object": "ball0", "host": "table"}}, names).holds(scene)
    assert parse(
        {"near": {"object": "ball0", "to": [-0.1, 0.3, 0.0], "radius": 0.01, "xy": True}}, names
    ).holds(scene)
    assert parse({"inside": {"object": "ball0", "box": [-0.2, 0.2, 0.0, 0.4]}}, names).holds(scene)
    assert not parse({"hidden": "ball0"}, names).holds(scene)
    assert parse({"all": [{"upright": "cup0"}, {"not": {"gone": "cup0"}}]}, names).holds(scene)
