"""Task files: a planning problem as a user writes it (JSON).

The fields, their types and their meaning are written once, in `planning/task_schema.py`
(docs/tasks.md shows them as tables). A PNG goal is RGB, or RGBA with depth (in [0, 1], near =
0) in the alpha channel; a .npy goal is a float (h, w, 3|4) array in [0, 1]. The paper drops
depth for negative goals so that lifting an object does not count as removing it (IV.C):
"channels": "rgb" does that.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
from PIL import Image

from afford.errors import UserError
from afford.planning.goal import CHANNELS, Goal, GoalError
from afford.planning.predicates import Predicate, PredicateError, parse
from afford.planning.sentence_goal import SentenceGoal, StatementHolds
from afford.planning.task_schema import TASK_FIELDS, fields_under
from afford.shipped import Nets
from afford.sim import camera as cam
from afford.sim.scene import SceneError, read_json_file, specs_from_json
from afford.words.facts import State
from afford.words.sentences import SentenceError
from afford.words.sentences import parse as parse_sentence

TASK_FORMAT = 1
MAX_STEPS_LIMIT = 8
REQUIRED = tuple(f.path for f in TASK_FIELDS if f.required == "yes")


class TaskError(UserError):
    """A task file that cannot be used; the message names the file and the field."""


@dataclass
class Task:
    name: str
    challenge: str
    scene: list  # list[ObjectSpec]
    goal: Goal | SentenceGoal
    max_steps: int
    success: Predicate | StatementHolds
    path: Path | None = None
    goal_scene: list | None = None  # the goal scene, when the goal was rendered from one
    crop: tuple[int, int, int, int] | None = None  # its pixel box (col, row, width, height)

    def object_names(self) -> list[str]:
        return object_names(self.scene)


def object_names(specs) -> list[str]:
    counts: dict[str, int] = {}
    names = []
    for s in specs:
        names.append(f"{s.kind}{counts.get(s.kind, 0)}")
        counts[s.kind] = counts.get(s.kind, 0) + 1
    return names


def load_task(path: str | Path, scene=None, nets: Nets | None = None) -> Task:
    """Read and validate a task file. A goal given as a scene is rendered with `scene` (a
    `Scene`, made here when not given); a goal in words is scored by the agreement model of
    `nets` (None: the package's)."""
    p = Path(path)
    obj = read_json_file(p, "task", TaskError)
    try:
        return task_from_json(obj, base=p.parent, scene=scene, path=p, nets=nets)
    except (SceneError, PredicateError, GoalError) as e:
        raise TaskError(f"{p.name}: {e}") from None


def task_from_json(
    obj: object, base: Path = Path("."), scene=None, path: Path | None = None, nets: Nets | None = None
) -> Task:
    where = path.name if path else "task"
    if not isinstance(obj, dict):
        raise TaskError(f"{where}: expected a JSON object")
    if obj.get("format", TASK_FORMAT) != TASK_FORMAT:
        raise TaskError(
            f"{where}.format: unknown task format {obj.get('format')!r} (this reads {TASK_FORMAT})"
        )
    known = fields_under()
    unknown = set(obj) - known
    if unknown:
        raise TaskError(f"{where}: unknown field {sorted(unknown)[0]!r}; expected {sorted(known)}")
    for key in REQUIRED:
        if key not in obj:
            raise TaskError(f"{where}: missing field {key!r}")
    specs = specs_from_json(obj["scene"], "scene")
    if not specs:
        raise TaskError(f"{where}.scene.objects: a task needs at least one object")
    max_steps = obj["max_steps"]
    if isinstance(max_steps, bool) or not isinstance(max_steps, int) or not 1 <= max_steps <= MAX_STEPS_LIMIT:
        raise TaskError(f"{where}.max_steps: expected a whole number from 1 to {MAX_STEPS_LIMIT}")
    success = parse(obj["success"], set(object_names(specs)))
    if scene is None:
        from afford.sim.scene import Scene

        scene = Scene()
    scene.reset(specs, settle=False, where="scene.")  # validated: nothing off the table, sunk or overlapping
    if isinstance(obj["goal"], dict) and "text" in obj["goal"]:
        goal, goal_scene, crop = _sentence_goal(obj["goal"], scene, nets), None, None
    else:
        goal, goal_scene, crop = _goal(obj["goal"], base, scene)
    return Task(
        name=str(obj.get("name", path.stem if path else "task")),
        challenge=str(obj.get("challenge", "")),
        scene=specs,
        goal=goal,
        max_steps=max_steps,
        success=success,
        path=path,
        goal_scene=goal_scene,
        crop=crop,
    )


def _sentence_goal(g: dict, scene, nets: Nets | None) -> SentenceGoal:
    """A goal sentence, read against the start scene (its words and the objects it names)."""
    if set(g) != {"text"} or not isinstance(g["text"], str):
        raise TaskError("goal: a sentence goal is {'text': '...'} and nothing else")
    try:
        return SentenceGoal(parse_sentence(g["text"], State.of_scene(scene)), nets=nets)
    except SentenceError as e:
        raise TaskError(f"goal.text: {e}") from None


def sentence_task(
    scene_path: str | Path, text: str, max_steps: int, scene=None, nets: Nets | None = None
) -> Task:
    """A scene file and a goal sentence (`afford plan --scene S.json --goal TEXT`), scored by
    the agreement model of `nets` (None: the package's): success is the sentence judged on the
    true poses after the plan."""
    p = Path(scene_path)
    specs = specs_from_json(read_json_file(p, "scene", TaskError), "scene")
    if not 1 <= max_steps <= MAX_STEPS_LIMIT:
        raise TaskError(f"--max-steps: expected a whole number from 1 to {MAX_STEPS_LIMIT}")
    if scene is None:
        from afford.sim.scene import Scene

        scene = Scene()
    scene.reset(specs, settle=False, where="scene.")
    goal = _sentence_goal({"text": text}, scene, nets)
    members = State.of_scene(scene).members
    return Task(p.stem, "", specs, goal, max_steps, StatementHolds(goal.statement, members), p)


def _goal(g: object, base: Path, scene) -> tuple[Goal, list | None, tuple | None]:
    if not isinstance(g, dict):
        raise TaskError("goal: expected an object with 'type' and 'image' or 'scene' + 'crop'")
    known = fields_under("goal")
    unknown = set(g) - known
    if unknown:
        raise TaskError(f"goal: unknown field {sorted(unknown)[0]!r}; expected {sorted(known)}")
    kind = g.get("type")
    if kind not in ("positive", "negative"):
        raise TaskError(f"goal.type: expected 'positive' or 'negative', not {kind!r}")
    negative = kind == "negative"
    channels = g.get("channels", "rgb" if negative else "rgbd")
    if channels not in CHANNELS:
        raise TaskError(f"goal.channels: expected one of {sorted(CHANNELS)}, not {channels!r}")
    if ("image" in g) == ("scene" in g):
        raise TaskError("goal: give either 'image' or 'scene' (with 'crop'), not both or neither")
    goal_scene = crop = None
    if "image" in g:
        patch = read_goal_image(base / str(g["image"]))
        if channels == "rgbd" and patch.shape[2] == 3:
            raise TaskError(f"goal.image: {g['image']} has no depth channel but goal.channels is 'rgbd'")
    else:
        if "crop" not in g:
            raise TaskError("goal.crop: a goal scene needs a crop box")
        goal_scene = specs_from_json(g["scene"], "goal.scene")
        crop = _crop(g["crop"])
        scene.reset(goal_scene, where="goal.scene.")
        col, row, w, h = crop
        patch = scene.observe()[row : row + h, col : col + w]
    return Goal(np.ascontiguousarray(patch[..., : CHANNELS[channels]]), negative), goal_scene, crop


def _crop(c: object) -> tuple[int, int, int, int]:
    size = cam.SIZE
    if isinstance(c, dict):
        centre, wh = c.get("centre"), c.get("size")
        ok = isinstance(centre, list) and len(centre) == 3 and isinstance(wh, list) and len(wh) == 2
        if not ok or not all(isinstance(v, int | float) and not isinstance(v, bool) for v in centre + wh):
            raise TaskError("goal.crop: expected {'centre': [x, y, z], 'size': [width, height]}")
        colrow = cam.world_to_pixel(np.asarray(centre, dtype=float))
        w, h = int(wh[0]), int(wh[1])
        box = [int(round(colrow[0] - w / 2)), int(round(colrow[1] - h / 2)), w, h]
    elif (
        isinstance(c, list) and len(c) == 4 and all(isinstance(v, int) and not isinstance(v, bool) for v in c)
    ):
        box = list(c)
    else:
        raise TaskError("goal.crop: expected [col, row, width, height] in whole pixels or a centre + size")
    col, row, w, h = box
    if w < 1 or h < 1 or col < 0 or row < 0 or col + w > size or row + h > size:
        raise TaskError(f"goal.crop: box {box} does not fit in the {size}x{size} state image")
    return col, row, w, h


def read_goal_image(path: Path) -> np.ndarray:
    """A goal patch from .npy (float, [0, 1]) or .png (RGB, or RGBA with depth as alpha)."""
    if not path.is_file():
        raise TaskError(f"goal.image: no such file {path}")
    if path.suffix == ".npy":
        try:
            patch = np.load(path, allow_pickle=False).astype(np.float32)
        except ValueError as e:
            raise TaskError(f"goal.image: {path.name} is not a readable .npy array ({e})") from None
    elif path.suffix == ".png":
        try:
            with Image.open(path) as im:
                im = im.convert("RGBA" if im.mode in ("RGBA", "LA") else "RGB")
                patch = np.asarray(im, dtype=np.float32) / 255.0
        except OSError as e:
            raise TaskError(f"goal.image: {path.name} is not a readable PNG ({e})") from None
    else:
        raise TaskError(f"goal.image: {path.name}: expected a .png or .npy file")
    if patch.ndim != 3 or patch.shape[2] not in (3, 4):
        raise TaskError(f"goal.image: {path.name} has shape {patch.shape}; expected (h, w, 3) or (h, w, 4)")
    if patch.shape[0] > cam.SIZE or patch.shape[1] > cam.SIZE:
        raise TaskError(f"goal.image: {path.name} is larger than the {cam.SIZE}x{cam.SIZE} state image")
    if not np.all(np.isfinite(patch)) or patch.min() < 0 or patch.max() > 1:
        raise TaskError(f"goal.image: {path.name} has values outside [0, 1]")
    return patch


def save_goal_png(patch: np.ndarray, path: str | Path) -> None:
    """Write a goal patch as PNG (RGBA carries depth) that `read_goal_image` reads back."""
    arr = (np.clip(patch, 0, 1) * 255 + 0.5).astype(np.uint8)
    Image.fromarray(arr, "RGBA" if arr.shape[2] == 4 else "RGB").save(path)
