"""Every file under tasks/ loads with the planner's own loader, and the task schema is one record."""

import json
import re
from pathlib import Path

import pytest

from afford.planning import predicates, task_schema
from afford.planning.tasks import load_task
from afford.sim.scene import load_scene_file

ROOT = Path(__file__).resolve().parents[1]
FILES = sorted((ROOT / "tasks").rglob("*.json"))


def test_the_task_folders_hold_what_the_docs_count():
    assert len(FILES) >= 43
    assert {f.parent.name for f in FILES} >= {"paper", "words", "variants", "uncertain", "continuous"}


@pytest.mark.parametrize("path", FILES, ids=[str(f.relative_to(ROOT / "tasks")) for f in FILES])
def test_every_task_file_loads_and_validates(scene, path):
    if "objects" in json.loads(path.read_text()):  # a scene file, for `afford plan --scene`
        scene.reset(load_scene_file(path), settle=False, where=f"{path.name}: ")
        return
    task = load_task(path, scene)
    assert 1 <= task.max_steps <= 8
    assert task.success.objects() <= set(task.object_names())
    # Every support shows in the start image (paper III.B: the state is seen top-down).
    scene.reset(task.scene)
    for name in task.object_names():
        if name.startswith("support"):
            assert scene.visible_pixels(name) >= 30, (name, scene.visible_pixels(name))


def test_the_schema_is_what_the_loader_and_the_predicates_read():
    assert set(task_schema.fields_under("goal")) == {"type", "channels", "image", "scene", "crop"}
    assert {p.name for p in task_schema.PREDICATES} == set(predicates._EVAL)
    hidden = next(p for p in task_schema.PREDICATES if p.name == "hidden")
    assert f"at most {predicates.HIDDEN_PIXELS} of its pixels" in hidden.holds


def test_the_docs_tables_are_generated_from_the_schema():
    page = (ROOT / "docs" / "tasks.md").read_text()
    for name, table in task_schema.markdown_tables().items():
        shown = re.search(rf"<!-- {name} -->\n(.*?)\n<!-- /{name} -->", page, re.S)
        assert shown, f"docs/tasks.md lacks the {name} markers"
        assert shown.group(1) == table, (
            f"docs/tasks.md's {name} table is stale: run python scripts/task_schema.py"
        )
