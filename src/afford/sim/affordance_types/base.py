"""The affordance-type record and its registry (see the package's docstring)."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass


@dataclass(frozen=True)
class AffordanceType:
    name: str
    holding: bool  # commenced while holding an object (else with the gripper empty)
    # Candidates at one object: find(scene, obj, consider, held_kind) calls
    # consider(type, point, tcp, angles, symmetric) for each; the detector keeps the reachable,
    # collision-free ones.
    find: Callable
    # At the commencement pose: act(scene, arm, affordance, tcp, q_at) -> message ("" if fine).
    act: Callable
    # The canonical effect on a symbolic state: canonical(world, state, affordance).
    canonical: Callable
    parameters: tuple[int, ...] = ()  # execution parameters the planner fills in (II.D)
    tcp_above: Callable | None = None  # tcp_above(scene): how far above the point the TCP goes
    colour: tuple[int, int, int] = (255, 255, 255)  # marker colour in pictures
    marker: float = 2.0  # marker radius in pictures, image pixels


REGISTRY: dict[str, AffordanceType] = {}


def register(kind: AffordanceType) -> AffordanceType:
    REGISTRY[kind.name] = kind
    return kind


def type_index(name: str) -> int:
    """A type's index in the data: its place in the registration order."""
    return list(REGISTRY).index(name)


def type_name(index: int) -> str:
    return list(REGISTRY)[index]
