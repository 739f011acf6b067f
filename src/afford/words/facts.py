"""What is true of a state, read from true poses: the relations goal sentences speak of.

A state here is what a dataset stores of it (the poses of every object slot, NaN rows for an
object off the table, and the slot the gripper holds), so every state of every sequence, and
every predicted state beside its true one, has known facts. A `Fact` is one relation between
an object slot and another slot or a word; `RELATIONS` says, for each, which kinds it speaks
of and what makes it true. The thresholds live in `sim/constants.WORDS`.
"""

from __future__ import annotations

import functools
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from afford.data.effects import axis_up, rested_on, slot_kind
from afford.sim.constants import EFFECTS, WORDS
from afford.sim.specs import REST_HALF_HEIGHT


@dataclass(frozen=True)
class State:
    """poses (slots, 7: x, y, z, qw, qx, qy, qz; NaN: off the table); held: a slot or -1;
    members: the slots of the scene's objects (those on the table at its start), so that an
    object gone since is told from a slot the scene never used; hidden: cups and balls on the
    table that the camera does not see (under the block, behind another)."""

    poses: np.ndarray
    held: int
    slots: tuple[str, ...]
    members: frozenset[int]
    hidden: frozenset[int] = frozenset()

    @classmethod
    def in_sequence(
        cls,
        poses: np.ndarray,
        held: np.ndarray,
        slots: tuple[str, ...],
        t: int,
        image: np.ndarray | None = None,
    ) -> State:
        """State t of a stored sequence (its poses and held slots per state); with the state's
        image (H, W, 4), the cups and balls it does not show are hidden."""
        members = frozenset(int(k) for k in np.flatnonzero(~np.isnan(poses[0, :, 0])))
        state = cls(poses[t], int(held[t]), tuple(slots), members)
        if image is None:
            return state
        return cls(state.poses, state.held, state.slots, members, hidden_in_image(state, image))

    @classmethod
    def of_scene(cls, scene, members: frozenset[int] | None = None) -> State:
        """A live scene's state; `members` default: the objects on the table now."""
        from afford.data.draws import pose_array

        poses = pose_array(scene)
        slots = tuple(name for name, _ in scene.slots)
        held = slots.index(scene.held) if scene.held else -1
        if members is None:
            members = frozenset(int(k) for k in np.flatnonzero(~np.isnan(poses[:, 0])))
        hidden = frozenset(
            k
            for k, name in enumerate(slots)
            if slot_kind(name) in COLOUR_TESTS
            and k != held
            and not np.isnan(poses[k, 0])
            and scene.visible_pixels(name) <= WORDS.hidden_pixels
        )
        return cls(poses, held, slots, members, hidden)

    @classmethod
    def of_specs(cls, specs, held: int = -1) -> State:
        """A scene description's state as written (ObjectSpecs: kind, pos, quat), neither
        simulated nor rendered, so nothing is hidden: what goal sentences are read against
        where no simulator is at hand (the goal grammar's test set and benchmark)."""
        from afford.sim.mjcf import slot_names

        slots = tuple(name for name, _ in slot_names())
        poses = np.full((len(slots), 7), np.nan, dtype=np.float32)
        counts: dict[str, int] = {}
        for spec in specs:
            name = f"{spec.kind}{counts.get(spec.kind, 0)}"
            counts[spec.kind] = counts.get(spec.kind, 0) + 1
            poses[slots.index(name)] = (*spec.pos, *spec.quat)
        members = frozenset(int(k) for k in np.flatnonzero(~np.isnan(poses[:, 0])))
        return cls(poses, held, slots, members)

    def kind(self, k: int) -> str:
        return slot_kind(self.slots[k])

    def present(self, k: int) -> bool:
        return not np.isnan(self.poses[k, 0])

    def standing(self, k: int) -> bool:
        """On the table's scene and not in the gripper: where relations between places hold."""
        return self.present(k) and k != self.held


# Which pixels show a cup (blue) or a ball (red) under the scene's light: (rgb (N, 3)) -> (N,).
COLOUR_TESTS = {
    "cup": lambda c: (c[:, 2] > 0.35) & (c[:, 2] > 1.8 * c[:, 0]) & (c[:, 2] > 1.5 * c[:, 1]),
    "ball": lambda c: (c[:, 0] > 0.45) & (c[:, 0] > 2.5 * c[:, 1]) & (c[:, 0] > 2.5 * c[:, 2]),
}


@functools.cache
def _grid(size: int) -> tuple[np.ndarray, np.ndarray]:
    return np.mgrid[0:size, 0:size]


def hidden_in_image(state: State, image: np.ndarray) -> frozenset[int]:
    """The cups and balls on the table of which `image` shows at most WORDS.hidden_pixels
    pixels of their colour near where their centre projects."""
    from afford.sim.camera import world_to_pixel

    rows, cols = _grid(image.shape[0])
    hidden = set()
    for k in range(len(state.slots)):
        if state.kind(k) not in COLOUR_TESTS or not state.standing(k):
            continue
        col, row = world_to_pixel(state.poses[k][None, :3].astype(float))[0]
        near = (cols + 0.5 - col) ** 2 + (rows + 0.5 - row) ** 2 <= WORDS.hidden_radius_px**2
        shown = COLOUR_TESTS[state.kind(k)](image[near][:, :3]).sum()
        if shown <= WORDS.hidden_pixels:
            hidden.add(k)
    return frozenset(hidden)


@dataclass(frozen=True)
class Fact:
    """One relation: its name (a key of RELATIONS), the object slot it is about, and its other
    argument: a slot, or a word (a side, an orientation, "table")."""

    relation: str
    subject: int
    other: int | str | None = None

    def holds(self, state: State) -> bool:
        return RELATIONS[self.relation].truth(state, self.subject, self.other)

    def clear(self, state: State) -> bool:
        """Is its truth clear of the vague edge of its words (WORDS.vague_m, vague_deg)?"""
        edge = EDGES.get(self.relation)
        return edge is None or edge(state, self.subject, self.other)


def _tilt(pose: np.ndarray) -> float:
    """Degrees between the body's axis and the vertical."""
    return float(np.degrees(np.arccos(np.clip(axis_up(pose)[2], -1.0, 1.0))))


def _yaw(pose: np.ndarray) -> float:
    """Degrees of the body's x axis about the vertical, in [0, 180): a block's long axis."""
    w, x, y, z = pose[3:7]
    return float(np.degrees(np.arctan2(2 * (w * z + x * y), 1 - 2 * (y * y + z * z))) % 180.0)


def on(s: State, k: int, host: int | str) -> bool:
    if not s.standing(k):
        return False
    if host == "table":
        return bool(s.poses[k, 2] < REST_HALF_HEIGHT[s.kind(k)] + WORDS.table_rise)
    return s.standing(host) and rested_on(s.poses[k], s.poses[host], s.kind(host))


def _block(s: State) -> int | None:
    return next((k for k in range(len(s.slots)) if s.kind(k) == "block" and s.standing(k)), None)


def across(s: State, k: int) -> bool:
    """The long axis runs left to right in the camera's view (world x), within the tolerance."""
    yaw = _yaw(s.poses[k])
    return min(yaw, 180.0 - yaw) <= WORDS.yaw_tolerance


def lengthwise(s: State, k: int) -> bool:
    return abs(_yaw(s.poses[k]) - 90.0) <= WORDS.yaw_tolerance


def lies(s: State, k: int, orientation: str) -> bool:
    """The block flat on its face (not tipped), lying across or lengthwise."""
    flat = s.standing(k) and not tipped(s, k)
    return flat and (across if orientation == "across" else lengthwise)(s, k)


def on_end(s: State, k: int, side: str) -> bool:
    """On the left or right end of the block lying across (world x: the camera's left-right)."""
    b = _block(s)
    if b is None or not on(s, k, b) or not across(s, b):
        return False
    offset = s.poses[k, 0] - s.poses[b, 0]
    return bool(offset < -WORDS.block_end if side == "left" else offset > WORDS.block_end)


def _apart_clear(s: State, k: int, other: int, axis: int) -> bool:
    if k == other or not (s.standing(k) and s.standing(other)):
        return True
    gap = abs(s.poses[other, axis] - s.poses[k, axis])
    return bool(abs(gap - WORDS.beside) > WORDS.vague_m)


def _lies_clear(s: State, k: int, orientation: str) -> bool:
    if not s.standing(k) or tipped(s, k):
        return True
    yaw = _yaw(s.poses[k])
    off = min(yaw, 180.0 - yaw) if orientation == "across" else abs(yaw - 90.0)
    return abs(off - WORDS.yaw_tolerance) > WORDS.vague_deg


def _on_end_clear(s: State, k: int, side: str) -> bool:
    b = _block(s)
    if b is None or not on(s, k, b) or not across(s, b):
        return True
    return bool(abs(abs(s.poses[k, 0] - s.poses[b, 0]) - WORDS.block_end) > WORDS.vague_m)


def tipped(s: State, k: int) -> bool:
    limit = EFFECTS.block_tip_deg if s.kind(k) == "block" else EFFECTS.topple_deg
    return s.standing(k) and _tilt(s.poses[k]) > limit


def _apart(s: State, k: int, other: int, axis: int, sign: float) -> bool:
    """Subject beside the other along a world axis by more than WORDS.beside (x: left-right,
    y: front-back, the camera looking along +y)."""
    if k == other or not (s.standing(k) and s.standing(other)):
        return False
    return bool(sign * (s.poses[other, axis] - s.poses[k, axis]) > WORDS.beside)


@dataclass(frozen=True)
class Relation:
    """Which kinds a relation speaks of, what its other argument may be (a slot of one of
    `other_kinds`, or one of `other_words`; neither: none), and its truth."""

    subjects: tuple[str, ...]
    truth: Callable[[State, int, int | str | None], bool]
    other_kinds: tuple[str, ...] = ()
    other_words: tuple[str, ...] = ()


SMALL = ("cup", "ball")
PLACED = ("cup", "ball", "support", "block")
RELATIONS: dict[str, Relation] = {
    "on": Relation(SMALL, on, ("block", "support"), ("table",)),
    "on_end": Relation(SMALL, on_end, (), ("left", "right")),
    "gone": Relation(SMALL, lambda s, k, o: not s.present(k) or k in s.hidden),
    "tipped": Relation(("cup", "support", "block"), lambda s, k, o: tipped(s, k)),
    "upright": Relation(("cup", "support", "block"), lambda s, k, o: s.standing(k) and not tipped(s, k)),
    "held": Relation(("cup", "ball", "block"), lambda s, k, o: s.held == k),
    "lies": Relation(("block",), lies, (), ("across", "lengthwise")),
    "left_of": Relation(PLACED, lambda s, k, o: _apart(s, k, o, 0, 1.0), PLACED),
    "right_of": Relation(PLACED, lambda s, k, o: _apart(s, k, o, 0, -1.0), PLACED),
    "in_front_of": Relation(PLACED, lambda s, k, o: _apart(s, k, o, 1, 1.0), PLACED),
    "behind": Relation(PLACED, lambda s, k, o: _apart(s, k, o, 1, -1.0), PLACED),
}
RELATION_NAMES = tuple(sorted(RELATIONS))  # in the order of their ids (model, evaluation)

# Where a relation's words are vague: (state, subject, other) -> its truth is clear of the edge.
EDGES: dict[str, Callable[[State, int, int | str | None], bool]] = {
    "left_of": lambda s, k, o: _apart_clear(s, k, o, 0),
    "right_of": lambda s, k, o: _apart_clear(s, k, o, 0),
    "in_front_of": lambda s, k, o: _apart_clear(s, k, o, 1),
    "behind": lambda s, k, o: _apart_clear(s, k, o, 1),
    "lies": _lies_clear,
    "on_end": _on_end_clear,
}
