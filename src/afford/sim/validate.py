"""Is a scene description one the simulator can start from? One place for every check.

Scene files, task files and the Python API (`Scene.reset`) all come here, so a bad start is
refused the same way everywhere: a `SceneError` (a `ValueError`) whose one line names where
(the file and the object's index and name) and the field. Checked, in this order:

- numbers: every position and quaternion component finite, the quaternion not zero;
- counts: at most LIMITS of each kind;
- place: the centre over the table (a footprint's margin inside its edge) and inside the
  camera's view, and not far above it;
- contacts, asked of MuJoCo with the objects posed and nothing simulated: no two objects, and
  no object and the table or the arm, interpenetrating beyond PENETRATION;
- support: nothing sunk into the table (its lowest point below the top by more than
  PENETRATION) or floating (its lowest point more than FLOAT above whatever is under it).
"""

from __future__ import annotations

from collections.abc import Sequence

import mujoco
import numpy as np

from afford.sim import camera as cam
from afford.sim.constants import BLOCK, LIMITS, TABLE
from afford.sim.specs import FOOTPRINT, SceneError

PENETRATION = 0.005  # metres of overlap allowed (settling pushes that much apart harmlessly)
FLOAT = 0.02  # metres of air allowed under an object's lowest point
RAY_START = 0.005  # rays start this far above the lowest point, outside whatever it touches
MAX_HEIGHT = 0.5  # metres above the table: no start pose is higher
# A horizontal radius that holds each kind, upright (the layouts' footprints); the block's is
# its width: its length may overhang the view's edge.
LIMIT = {"cup": LIMITS.cups, "ball": LIMITS.balls, "support": LIMITS.supports, "block": LIMITS.blocks}


def label(index: int, name: str, where: str) -> str:
    return f"{where}objects[{index}] ({name})"


def check_numbers(specs: Sequence, where: str = "") -> list[str]:
    """The names the objects get (cup0, ...); raises on non-finite numbers and too many of a kind."""
    counts = {k: 0 for k in LIMIT}
    names = []
    for i, s in enumerate(specs):
        if s.kind not in LIMIT:
            raise SceneError(
                f"{where}objects[{i}].kind: unknown object kind {s.kind!r}; expected one of {sorted(LIMIT)}"
            )
        name = f"{s.kind}{counts[s.kind]}"
        at = label(i, name, where)
        pos, quat = np.asarray(s.pos, dtype=float), np.asarray(s.quat, dtype=float)
        if pos.shape != (3,) or not np.all(np.isfinite(pos)):
            raise SceneError(f"{at}.pos: expected 3 finite numbers, got {_numbers(s.pos)}")
        if quat.shape != (4,) or not np.all(np.isfinite(quat)) or np.linalg.norm(quat) < 1e-6:
            raise SceneError(f"{at}.quat: expected 4 finite numbers, not all zero, got {_numbers(s.quat)}")
        if counts[s.kind] >= LIMIT[s.kind]:
            raise SceneError(f"{at}: too many {s.kind}s: a scene holds at most {LIMIT[s.kind]}")
        counts[s.kind] += 1
        names.append(name)
    return names


def _numbers(values) -> str:
    return "[" + ", ".join(f"{float(v):g}" for v in np.ravel(values)) + "]"


def check_place(specs: Sequence, names: list[str], where: str = "") -> None:
    """Centre over the table, in the camera's view, and not high in the air."""
    lo = np.subtract(TABLE.centre, TABLE.half)
    hi = np.add(TABLE.centre, TABLE.half)
    for i, (s, name) in enumerate(zip(specs, names, strict=True)):
        at = label(i, name, where)
        x, y, z = (float(v) for v in s.pos)
        r = FOOTPRINT[s.kind]
        for axis, v, a, b in (("x", x, lo[0], hi[0]), ("y", y, lo[1], hi[1])):
            if not a + r <= v <= b - r:
                raise SceneError(
                    f"{at}.pos: {axis} = {v:.3g} is off the table ({a + r:.3f} to {b - r:.3f} for a {s.kind})"
                )
        col, row = cam.world_to_pixel(np.array([x, y, z]))
        if not (0 <= col < cam.SIZE and 0 <= row < cam.SIZE):
            raise SceneError(f"{at}.pos: ({x:.3g}, {y:.3g}) is outside the camera's view")
        if z > MAX_HEIGHT:
            raise SceneError(f"{at}.pos: z = {z:.3g} is more than {MAX_HEIGHT} m above the table")


def check_contacts(scene, names: list[str], where: str = "") -> None:
    """With the objects posed and `mj_forward` run (nothing simulated): interpenetration and
    support, from MuJoCo's contacts and rays."""
    model, data = scene.model, scene.data
    body_of = {scene.body_id(n): n for n in names}
    table = model.geom("table").id
    index = {n: i for i, n in enumerate(names)}

    def who(geom: int) -> str | None:
        if geom == table:
            return "the table"
        body = int(model.geom_bodyid[geom])
        while body not in body_of and body != 0:
            body = int(model.body_parentid[body])
        return body_of.get(body, "the arm" if body != 0 else None)

    worst = None  # the deepest interpenetration: what a reader should fix first
    for c in data.contact[: data.ncon]:
        a, b = who(c.geom1), who(c.geom2)
        objs = [n for n in (a, b) if n in index]
        if c.dist >= -PENETRATION or not objs or a == b or (worst and c.dist >= worst[0]):
            continue
        first = min(objs, key=index.get)
        worst = (c.dist, first, b if first == a else a)
    if worst:
        depth, first, other = worst
        what = "sunk {:.1f} cm into the table" if other == "the table" else f"overlaps {other} by {{:.1f}} cm"
        raise SceneError(f"{label(index[first], first, where)}.pos: " + what.format(-depth * 100))
    for n in names:
        low = scene.lowest_point(n)
        if low < -PENETRATION:
            raise SceneError(f"{label(index[n], n, where)}.pos: sunk {-low * 100:.1f} cm into the table")
        gap = _air_below(scene, n, low)
        if gap > FLOAT:
            raise SceneError(
                f"{label(index[n], n, where)}.pos: floats {gap * 100:.1f} cm above what is under it"
            )


def _air_below(scene, name: str, low: float) -> float:
    """Height of the air under an object's lowest point: rays cast straight down from points
    along its own axes (the block's whole length), ignoring the object itself; the least gap
    counts."""
    o = scene.object(name)
    along = np.linspace(-0.9, 0.9, 9) * (BLOCK.half[0] if o.kind == "block" else FOOTPRINT[o.kind])
    across = 0.7 * FOOTPRINT[o.kind]
    rot = np.zeros(9)
    mujoco.mju_quat2Mat(rot, o.quat)
    ax, ay = rot.reshape(3, 3)[:2, 0], rot.reshape(3, 3)[:2, 1]
    body = scene.body_id(name)
    geom = np.zeros(1, dtype=np.int32)
    down = np.array([0.0, 0.0, -1.0])
    gaps = []
    for off in [t * ax for t in along] + [across * ay, -across * ay]:
        start = np.array([o.pos[0] + off[0], o.pos[1] + off[1], low + RAY_START])
        d = mujoco.mj_ray(scene.model, scene.data, start, down, None, 1, body, geom)
        if d >= 0:
            gaps.append(d - RAY_START)
    return min(gaps) if gaps else 0.0
