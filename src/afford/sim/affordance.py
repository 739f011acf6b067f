"""The affordance record, and the two forms it takes on its way from the nets to the arm.

An `Affordance` is where and how an action can be commenced (paper II.A). As the nets see it,
and as the dataset stores it, it is a row of 7 floats (`AFF_COLUMNS`, read by `Col`): the
recognition net's targets, the prediction net's action input (paper II.C) and the planners'
batches are all built from rows. A recognised affordance carries the recognition net's
confidence with it (`Detection`); the ground truth, the oracle and the symbolic planner give
theirs confidence 1. This module needs nothing but the type registry, so every layer can use it.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, replace

import numpy as np

from afford.sim.affordance_types import REGISTRY, type_index, type_name

# An affordance row: type index, x, y, z, angle (degrees), symmetric (0/1), turn (degrees; 0: none).
AFF_COLUMNS = ("type", "x", "y", "z", "angle", "symmetric", "turn")
AFF_WIDTH = len(AFF_COLUMNS)


class Col:
    """Where each of AFF_COLUMNS sits in a row: code reads rows by these names, not numbers."""

    TYPE, X, Y, Z, ANGLE, SYMMETRIC, TURN = range(AFF_WIDTH)
    POSITION = slice(X, Z + 1)  # x, y, z
    XY = slice(X, Y + 1)


@dataclass(frozen=True)
class Affordance:
    """One affordance: where and how an action can be commenced.

    type: grasp, place or turn. position: the target point (x, y, z) in metres, world frame:
    an object's centre for grasp and turn, a point on a surface for place. angle: gripper yaw
    in degrees, [0, 360), the direction the fingers open along. symmetric: other angles at the
    same point give equivalent results. turn: the turn affordance's execution parameter in
    degrees, counter-clockwise seen from above: +90 or -90 in the paper (II.D fills it in), any
    angle in [-180, 180] with continuous turns (paper V); 0 for other types and for a turn not
    yet parametrised.
    """

    type: str
    position: tuple[float, float, float]
    angle: float
    symmetric: bool
    turn: float = 0

    def __post_init__(self):
        if self.type not in REGISTRY:
            raise ValueError(f"unknown affordance type {self.type!r}; expected one of {tuple(REGISTRY)}")
        if not (np.isfinite(self.turn) and -180 <= self.turn <= 180):
            raise ValueError(f"turn must be an angle in [-180, 180] degrees (0: none), not {self.turn}")

    def with_turn(self, turn: float) -> Affordance:
        return replace(self, turn=turn)

    def to_dict(self) -> dict:
        d = asdict(self)
        d["position"] = [round(float(v), 5) for v in self.position]
        d["angle"] = round(float(self.angle), 3)
        return d

    @staticmethod
    def from_dict(d: dict) -> Affordance:
        return Affordance(
            d["type"],
            tuple(float(v) for v in d["position"]),
            float(d["angle"]),
            bool(d["symmetric"]),
            float(d.get("turn", 0)),
        )


@dataclass(frozen=True)
class Detection:
    """An affordance with the confidence it was recognised with (1 for ground truth)."""

    affordance: Affordance
    score: float = 1.0


def encode_affordance(a: Affordance) -> np.ndarray:
    row = np.zeros(AFF_WIDTH, dtype=np.float32)
    row[Col.TYPE], row[Col.POSITION], row[Col.ANGLE] = type_index(a.type), a.position, a.angle
    row[Col.SYMMETRIC], row[Col.TURN] = float(a.symmetric), a.turn
    return row


def decode_affordance(row: np.ndarray) -> Affordance:
    return Affordance(
        type_name(int(row[Col.TYPE])),
        tuple(float(v) for v in row[Col.POSITION]),
        float(row[Col.ANGLE]),
        bool(row[Col.SYMMETRIC] > 0.5),
        float(row[Col.TURN]),
    )
