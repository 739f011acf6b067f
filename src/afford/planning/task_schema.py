"""The task file's schema and its success predicates, written once.

`planning/tasks.py` and `planning/predicates.py` read the field names they accept from here, and
`scripts/task_schema.py` writes the tables of docs/tasks.md from here (a test checks the page
matches), so the loader, the page and this record cannot disagree.
"""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class Field:
    """One field of a task file: `path` names it from the file's top ("goal.crop")."""

    path: str
    type: str
    required: str
    meaning: str


TASK_FIELDS: tuple[Field, ...] = (
    Field("format", "1", "no", "the task format; this version reads 1"),
    Field("name", "text", "no", "the task's name in records and pictures (default: the file's name)"),
    Field("challenge", "text", "no", "what makes the task hard, in a sentence or two"),
    Field(
        "scene",
        '`{"objects": [...]}`',
        "yes",
        "the start scene, as `afford scene --save` writes it; each object has `kind` (cup, ball, "
        "support, block), `pos` [x, y, z] in metres and `yaw` in degrees or `quat` [w, x, y, z]",
    ),
    Field(
        "goal",
        "object",
        "yes",
        '`{"text": "..."}`, a sentence (paper V), or an image goal made of the fields below',
    ),
    Field("goal.type", "`positive` or `negative`", "image goals", "reach the patch, or move away from it"),
    Field(
        "goal.channels",
        "`rgbd` or `rgb`",
        "no",
        "what eq. (5) compares (default: `rgbd` for positive goals, `rgb` for negative ones, as in "
        "the paper, so that lifting an object does not count as removing it)",
    ),
    Field(
        "goal.image",
        "file name",
        "`image` or `scene`",
        "a goal patch beside the task file: `.png` (RGB, or RGBA with depth in the alpha channel, "
        "near = 0) or `.npy` (float (h, w, 3 or 4) in [0, 1])",
    ),
    Field(
        "goal.scene",
        '`{"objects": [...]}`',
        "`image` or `scene`",
        "a goal scene the tool renders; the patch is its crop",
    ),
    Field(
        "goal.crop",
        '[col, row, width, height] or `{"centre": [x, y, z], "size": [w, h]}`',
        "with `goal.scene`",
        "the patch's box in the 128 x 128 image: in whole pixels, or around a world point given in "
        "metres, with its width and height in pixels",
    ),
    Field("max_steps", "whole number, 1-8", "yes", "the longest plan the planner may search"),
    Field(
        "success",
        "predicate",
        "yes",
        "what the executed plan must achieve, on true poses (the predicates below); the planner "
        "never sees it",
    ),
)


@dataclass(frozen=True)
class PredicateForm:
    """One success predicate: its JSON form and when it holds."""

    name: str
    form: str
    holds: str


PREDICATES: tuple[PredicateForm, ...] = (
    PredicateForm(
        "near",
        '{"near": {"object": "cup0", "to": [x, y, z], "radius": 0.03, "xy": false}}',
        "the object's centre is within `radius` metres of `to` (`xy`: ignoring height; default false)",
    ),
    PredicateForm(
        "yaw",
        '{"yaw": {"object": "block0", "to": 90, "tolerance": 15, "period": 180}}',
        "its yaw is within `tolerance` degrees of `to`, modulo `period` (defaults 15 and 360)",
    ),
    PredicateForm(
        "on",
        '{"on": {"object": "cup0", "host": "block0"}}',
        "it rests on the host's top: a support, the block or `table`",
    ),
    PredicateForm("upright", '{"upright": "cup0"}', "its axis is within about 25 degrees of vertical"),
    PredicateForm("gone", '{"gone": "ball0"}', "it fell off the table"),
    PredicateForm("hidden", '{"hidden": "ball0"}', "gone, or at most 3 of its pixels visible to the camera"),
    PredicateForm(
        "inside",
        '{"inside": {"object": "ball0", "box": [x0, y0, x1, y1]}}',
        "its centre lies inside that area of the table (metres)",
    ),
    PredicateForm("held", '{"held": "cup0"}', "the gripper holds it"),
    PredicateForm("all", '{"all": [...]}', "every predicate of the list holds"),
    PredicateForm("any", '{"any": [...]}', "at least one of them holds"),
    PredicateForm("not", '{"not": {...}}', "the predicate does not hold"),
)


def fields_under(prefix: str = "") -> set[str]:
    """The field names directly under `prefix` ("" for the top, "goal" for the goal's)."""
    start = f"{prefix}." if prefix else ""
    return {
        f.path[len(start) :]
        for f in TASK_FIELDS
        if f.path.startswith(start) and "." not in f.path[len(start) :]
    }


def _cell(text: str) -> str:
    return text.replace("|", "\\|")


def markdown_tables() -> dict[str, str]:
    """The tables docs/tasks.md shows, by the name of the marker that holds each."""
    fields = ["| field | type | required | meaning |", "|---|---|---|---|"]
    fields += [
        f"| `{f.path}` | {_cell(f.type)} | {_cell(f.required)} | {_cell(f.meaning)} |" for f in TASK_FIELDS
    ]
    preds = ["| predicate | form | holds when |", "|---|---|---|"]
    preds += [f"| `{p.name}` | `{_cell(p.form)}` | {_cell(p.holds)} |" for p in PREDICATES]
    return {"task-fields": "\n".join(fields), "predicates": "\n".join(preds)}
