"""The scene's records: object kinds and poses, the scene-file JSON, and the one error type.

A leaf of the simulator package (it needs no MuJoCo): the scene, the random layouts and the
start validation all read these, and none of them needs the others to do so.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from afford.errors import UserError
from afford.sim.constants import BALL, BLOCK, CUP, SUPPORT

REST_HALF_HEIGHT = {
    "cup": CUP.height / 2,
    "ball": BALL.radius,
    "support": SUPPORT.half[2],
    "block": BLOCK.half[2],
}
SCENE_FORMAT = 1


class SceneError(UserError):
    """A scene description that cannot be loaded; the message names the problem."""


@dataclass
class ObjectSpec:
    """One object of a scene description: its kind and pose (quaternion w, x, y, z)."""

    kind: str
    pos: tuple[float, float, float]
    quat: tuple[float, float, float, float] = (1.0, 0.0, 0.0, 0.0)

    @staticmethod
    def upright(kind: str, x: float, y: float, yaw_deg: float = 0.0, z: float = 0.0) -> ObjectSpec:
        """An object standing on a surface at height z (0 = the table top)."""
        half = np.radians(yaw_deg) / 2
        return ObjectSpec(kind, (x, y, z + REST_HALF_HEIGHT[kind]), (np.cos(half), 0.0, 0.0, np.sin(half)))


# The radius of the circle an object's footprint fits in, at any yaw (the block's: its half
# width; layouts place the block by circles along it).
FOOTPRINT = {
    "cup": CUP.radius,
    "ball": BALL.radius,
    "support": float(np.hypot(*SUPPORT.foot_half[:2])),  # the foot's: wider than the post
    "block": BLOCK.half[1],
}


def specs_to_json(specs: list[ObjectSpec]) -> dict:
    return {
        "format": SCENE_FORMAT,
        "objects": [{"kind": s.kind, "pos": list(s.pos), "quat": list(s.quat)} for s in specs],
    }


def specs_from_json(obj: object, where: str = "scene") -> list[ObjectSpec]:
    """Parse a scene description; every mistake raises SceneError naming the field."""
    if not isinstance(obj, dict):
        raise SceneError(f"{where}: expected a JSON object with an 'objects' list")
    if obj.get("format", SCENE_FORMAT) != SCENE_FORMAT:
        raise SceneError(
            f"{where}.format: unknown scene format {obj.get('format')!r} (this version reads {SCENE_FORMAT})"
        )
    items = obj.get("objects")
    if not isinstance(items, list):
        raise SceneError(f"{where}.objects: expected a list of objects")
    specs = []
    for i, item in enumerate(items):
        at = f"{where}.objects[{i}]"
        if not isinstance(item, dict):
            raise SceneError(f"{at}: expected an object with 'kind' and 'pos'")
        kind = item.get("kind")
        if kind not in REST_HALF_HEIGHT:
            raise SceneError(f"{at}.kind: {kind!r} is not one of {sorted(REST_HALF_HEIGHT)}")
        pos = _vector(item.get("pos"), 3, f"{at}.pos")
        if "quat" in item and "yaw" in item:
            raise SceneError(f"{at}: give either 'quat' or 'yaw', not both")
        if "yaw" in item:
            yaw = _vector([item["yaw"]], 1, f"{at}.yaw")[0]
            half = np.radians(yaw) / 2
            quat = (float(np.cos(half)), 0.0, 0.0, float(np.sin(half)))
        else:
            quat = _vector(item.get("quat", [1, 0, 0, 0]), 4, f"{at}.quat")
            if np.linalg.norm(quat) < 1e-6:
                raise SceneError(f"{at}.quat: a quaternion cannot be zero")
        specs.append(ObjectSpec(kind, pos, quat))
    return specs


def _vector(value: object, n: int, where: str) -> tuple[float, ...]:
    if not isinstance(value, list | tuple) or len(value) != n:
        raise SceneError(f"{where}: expected a list of {n} numbers")
    out = []
    for v in value:
        if isinstance(v, bool) or not isinstance(v, int | float) or not np.isfinite(v):
            raise SceneError(f"{where}: expected a list of {n} numbers, got {value!r}")
        out.append(float(v))
    return tuple(out)


def read_json_file(path: str | Path, what: str, error: type[ValueError] = SceneError) -> object:
    """A JSON file's content; a missing or unparsable file raises `error` in one line."""
    p = Path(path)
    if not p.is_file():
        raise error(f"{p}: no such {what} file")
    try:
        return json.loads(p.read_text())
    except json.JSONDecodeError as e:
        raise error(f"{p}: not valid JSON ({e.msg} at line {e.lineno})") from None


def load_scene_file(path: str | Path) -> list[ObjectSpec]:
    return specs_from_json(read_json_file(path, "scene"), where=Path(path).name)


def save_scene_file(path: str | Path, specs: list[ObjectSpec]) -> None:
    Path(path).write_text(json.dumps(specs_to_json(specs), indent=2) + "\n")
