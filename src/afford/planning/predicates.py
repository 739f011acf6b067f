"""Success predicates: what a task's goal means, stated on true object poses.

The planner never sees these (it sees only the goal image); they judge whether an executed
plan did what the task asked. A predicate is a small JSON tree; its forms, and when each
holds, are written once in `planning/task_schema.PREDICATES` (a test checks they match `_EVAL`).

Objects are named by kind and order of appearance in the task's scene: cup0, cup1, ball0,
support0, block0.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from afford.errors import UserError
from afford.sim.constants import TOLERANCES
from afford.sim.resting import HOST_HALF, rests_on

HIDDEN_PIXELS = 3  # a few stray pixels at an edge do not make an object visible
UPRIGHT_COS = TOLERANCES.upright_cos


class PredicateError(UserError):
    """A predicate that cannot be read; the message names the field."""


@dataclass(frozen=True)
class Predicate:
    """One node of a predicate tree: an operator, its arguments, its children."""

    op: str
    args: dict
    children: tuple[Predicate, ...] = ()

    def holds(self, scene, see: bool = True) -> bool:
        """Does it hold in the scene's current state? With see=False visibility is not
        judged from the camera: `hidden` then means `gone` (a symbolic state has no view)."""
        return _EVAL[self.op](self, scene, see)

    def objects(self) -> set[str]:
        names = {self.args["object"]} if "object" in self.args else set()
        if self.args.get("host", "table") != "table":
            names.add(self.args["host"])
        for c in self.children:
            names |= c.objects()
        return names

    def describe(self) -> str:
        if self.op in ("all", "any"):
            return f" {'and' if self.op == 'all' else 'or'} ".join(f"({c.describe()})" for c in self.children)
        if self.op == "not":
            return f"not ({self.children[0].describe()})"
        a = self.args
        if self.op == "near":
            return f"{a['object']} within {a['radius']} m of {a['to']}{' (xy)' if a['xy'] else ''}"
        if self.op == "yaw":
            return f"{a['object']} yaw {a['to']} +- {a['tolerance']} deg"
        if self.op == "on":
            return f"{a['object']} on {a['host']}"
        if self.op == "inside":
            return f"{a['object']} inside {a['box']}"
        return f"{a['object']} {self.op}"


# ---------------------------------------------------------------------------- evaluation
def _near(p: Predicate, scene, see: bool) -> bool:
    o = scene.object(p.args["object"])
    if not o.present or o.held:
        return False
    d = o.pos - np.asarray(p.args["to"])
    if p.args["xy"]:
        d = d[:2]
    return bool(np.linalg.norm(d) <= p.args["radius"])


def _yaw(p: Predicate, scene, see: bool) -> bool:
    o = scene.object(p.args["object"])
    period = p.args["period"]
    diff = (o.yaw_deg - p.args["to"] + period / 2) % period - period / 2
    return bool(o.present and abs(diff) <= p.args["tolerance"])


def _on(p: Predicate, scene, see: bool) -> bool:
    return rests_on(scene, p.args["object"], p.args["host"])


def _upright(p: Predicate, scene, see: bool) -> bool:
    o = scene.object(p.args["object"])
    return bool(o.present and o.up_axis[2] > UPRIGHT_COS)


def _gone(p: Predicate, scene, see: bool) -> bool:
    return not scene.object(p.args["object"]).present


def _hidden(p: Predicate, scene, see: bool) -> bool:
    name = p.args["object"]
    if not scene.object(name).present:
        return True
    return see and scene.visible_pixels(name) <= HIDDEN_PIXELS


def _inside(p: Predicate, scene, see: bool) -> bool:
    o = scene.object(p.args["object"])
    x0, y0, x1, y1 = p.args["box"]
    return bool(o.present and x0 <= o.pos[0] <= x1 and y0 <= o.pos[1] <= y1)


def _held(p: Predicate, scene, see: bool) -> bool:
    return scene.held == p.args["object"]


_EVAL = {
    "near": _near,
    "yaw": _yaw,
    "on": _on,
    "upright": _upright,
    "gone": _gone,
    "hidden": _hidden,
    "inside": _inside,
    "held": _held,
    "all": lambda p, s, see: all(c.holds(s, see) for c in p.children),
    "any": lambda p, s, see: any(c.holds(s, see) for c in p.children),
    "not": lambda p, s, see: not p.children[0].holds(s, see),
}


# ---------------------------------------------------------------------------- parsing
def parse(obj: object, names: set[str], where: str = "success") -> Predicate:
    """Read a predicate tree; `names` are the objects the task's scene has."""
    if not isinstance(obj, dict) or len(obj) != 1:
        raise PredicateError(f"{where}: expected an object with one key, one of {sorted(_EVAL)}")
    ((op, arg),) = obj.items()
    at = f"{where}.{op}"
    if op not in _EVAL:
        raise PredicateError(f"{where}: unknown predicate {op!r}; expected one of {sorted(_EVAL)}")
    if op in ("all", "any"):
        if not isinstance(arg, list) or not arg:
            raise PredicateError(f"{at}: expected a non-empty list of predicates")
        return Predicate(op, {}, tuple(parse(c, names, f"{at}[{i}]") for i, c in enumerate(arg)))
    if op == "not":
        return Predicate(op, {}, (parse(arg, names, at),))
    if op in ("upright", "gone", "hidden", "held"):
        return Predicate(op, {"object": _name(arg, names, at)})
    if not isinstance(arg, dict):
        raise PredicateError(f"{at}: expected an object with an 'object' field")
    args = {"object": _name(arg.get("object"), names, f"{at}.object")}
    if op == "near":
        args["to"] = _numbers(arg.get("to"), 3, f"{at}.to")
        args["radius"] = _positive(arg.get("radius"), f"{at}.radius")
        args["xy"] = bool(arg.get("xy", False))
    elif op == "yaw":
        args["to"] = _numbers([arg.get("to")], 1, f"{at}.to")[0]
        args["tolerance"] = _positive(arg.get("tolerance", 15.0), f"{at}.tolerance")
        args["period"] = _positive(arg.get("period", 360.0), f"{at}.period")
    elif op == "on":
        host = arg.get("host")
        if host != "table":
            host = _name(host, names, f"{at}.host")
            if host.rstrip("0123456789") not in HOST_HALF:
                raise PredicateError(
                    f"{at}.host: {host} cannot hold things; use a support, the block or 'table'"
                )
        args["host"] = host
    elif op == "inside":
        box = _numbers(arg.get("box"), 4, f"{at}.box")
        if box[0] >= box[2] or box[1] >= box[3]:
            raise PredicateError(f"{at}.box: expected [x0, y0, x1, y1] with x0 < x1 and y0 < y1")
        args["box"] = box
    unknown = set(arg) - set(args) - {"object"}
    if unknown:
        raise PredicateError(f"{at}: unknown field {sorted(unknown)[0]!r}")
    return Predicate(op, args)


def _name(value: object, names: set[str], where: str) -> str:
    if not isinstance(value, str) or value not in names:
        raise PredicateError(f"{where}: {value!r} is not an object of the scene ({', '.join(sorted(names))})")
    return value


def _numbers(value: object, n: int, where: str) -> tuple[float, ...]:
    ok = isinstance(value, list | tuple) and len(value) == n
    if ok:
        ok = all(isinstance(v, int | float) and not isinstance(v, bool) and np.isfinite(v) for v in value)
    if not ok:
        raise PredicateError(f"{where}: expected {'a number' if n == 1 else f'a list of {n} numbers'}")
    return tuple(float(v) for v in value)


def _positive(value: object, where: str) -> float:
    v = _numbers([value], 1, where)[0]
    if v <= 0:
        raise PredicateError(f"{where}: must be positive")
    return v
