"""What an execution did, read from true poses: canonical, or which side effects it had.

The paper's claim (I, IV.C) is about non-canonical effects: an action changes more than the
object it acts on. This module is the one definition of them, shared by `afford data info`
(counts per kind), the prediction evaluation (foresight per kind, Table 2 split), the training
sampler that draws side-effect runs more often, and the pictures.

An execution acts on one object: the object grasped, the object placed (held before), or the
block turned. Every other object on the table may be
- pushed: moved more than `EFFECTS.moved` metres across the table;
- toppled: its axis turned more than `EFFECTS.topple_deg` (cups, supports; a ball's axis
  means nothing);
- off the table: on the table before, gone after;
- carried: it rested on the acted-on object and moved with it (a cup on a turning block);
and the acted-on object itself, when placed, stays where it was put, slides (ends more than
`EFFECTS.moved` from the place point) or falls (off the table, toppled, or more than
`EFFECTS.drop` below the place point). A block not held after the step that tilted by more
than `EFFECTS.block_tip_deg` tipped, whichever object was acted on.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from afford.sim.affordance import Col
from afford.sim.affordances import TYPES
from afford.sim.camera import SIZE, world_to_pixel
from afford.sim.constants import BALL, BLOCK, CUP, EFFECTS, SUPPORT

PUSHED, TOPPLED, OFF_TABLE, CARRIED = "pushed", "toppled", "off the table", "carried"
BLOCK_TIPS, PLACED_SLIDES, PLACED_FALLS = "block tips", "placed slides", "placed falls"
# Every side-effect kind, in the order tables list them.
KINDS = (PUSHED, TOPPLED, OFF_TABLE, CARRIED, BLOCK_TIPS, PLACED_SLIDES, PLACED_FALLS)
CANONICAL = "canonical"
RADIUS_PX = 7  # where an object's effect shows: a disk this wide around it in the image
# Half the top face of each kind that something can rest on (metres along its x and y axes).
FOOTPRINT_HALF = {
    "block": BLOCK.half[:2],
    "support": SUPPORT.half[:2],
    "cup": (CUP.radius, CUP.radius),
    "ball": (BALL.radius, BALL.radius),
}


@dataclass(frozen=True)
class Effect:
    """One side effect: its kind and the object slot that took it."""

    kind: str
    slot: int


@dataclass(frozen=True)
class StepEffects:
    """What one execution did: its type, the object it acted on, and its side effects."""

    type: str
    acted: int | None  # slot of the acted-on object (None: nothing found at the action)
    effects: tuple[Effect, ...]

    @property
    def canonical(self) -> bool:
        return not self.effects

    @property
    def kinds(self) -> set[str]:
        return {e.kind for e in self.effects}

    @property
    def affected(self) -> list[int]:
        """The slots that took a side effect, each once, in slot order."""
        return sorted({e.slot for e in self.effects})


def slot_kind(slot: str) -> str:
    return slot.rstrip("0123456789")


def axis_up(pose: np.ndarray) -> np.ndarray:
    """The body's z axis in the world, from a pose row (x, y, z, qw, qx, qy, qz)."""
    w, x, y, z = pose[3:7]
    return np.array([2 * (x * z + w * y), 2 * (y * z - w * x), 1 - 2 * (x * x + y * y)])


def tilt_deg(before: np.ndarray, after: np.ndarray) -> float:
    """How far the body's z axis turned between two poses, in degrees."""
    cos = float(np.clip(np.dot(axis_up(before), axis_up(after)), -1.0, 1.0))
    return float(np.degrees(np.arccos(cos)))


def _present(pose: np.ndarray) -> bool:
    return not np.isnan(pose[0])


def acted_slot(before: np.ndarray, held_before: int, held_after: int, action: np.ndarray) -> int | None:
    """The slot an execution acts on: what it grasps, what it places, what it turns."""
    kind = TYPES[int(action[Col.TYPE])]
    if kind == "place" and held_before >= 0:
        return held_before
    if kind == "grasp" and held_after >= 0:
        return held_after
    present = [k for k in range(len(before)) if _present(before[k]) and k != held_before]
    if not present:
        return None
    at = action[Col.POSITION]
    return min(present, key=lambda k: float(np.linalg.norm(before[k, :2] - at[:2])))


def planar_axes(pose: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """An object's x axis projected on the table's plane, and that turned a quarter left: the
    directions along and across a block (of unit length while it lies flat)."""
    w, x, y, z = pose[3:7]
    along = np.array([1 - 2 * (y * y + z * z), 2 * (x * y + w * z)])
    return along, np.array([-along[1], along[0]])


def rested_on(rider: np.ndarray, host: np.ndarray, host_kind: str) -> bool:
    """Was `rider` on top of `host`: above its centre, and over its top face (in the host's
    frame, so a cup beside the long block is not on it)?"""
    if rider[2] < host[2] + EFFECTS.rider_rise:
        return False
    along, across = planar_axes(host)
    offset = rider[:2] - host[:2]
    half = FOOTPRINT_HALF[host_kind]
    margin = EFFECTS.rider_margin
    return bool(abs(offset @ along) < half[0] + margin and abs(offset @ across) < half[1] + margin)


def step_effects(
    before: np.ndarray,
    after: np.ndarray,
    held_before: int,
    held_after: int,
    action: np.ndarray,
    slots: tuple[str, ...],
) -> StepEffects:
    """Label one execution: poses (slots, 7) before and after (NaN rows: not on the table),
    the held slot before and after (-1: none), the executed affordance row (format.Col)."""
    kind = TYPES[int(action[Col.TYPE])]
    acted = acted_slot(before, held_before, held_after, action)
    found: list[Effect] = []
    for k, name in enumerate(slots):
        if not _present(before[k]):
            continue
        if k == acted:
            if kind == "place":
                found += _placed(after[k], k, action, slot_kind(name))
            elif slot_kind(name) == "block" and held_after != k and _tipped(after[k], EFFECTS.block_tip_deg):
                found.append(Effect(BLOCK_TIPS, k))  # a turn that left the block tilted
            continue
        if not _present(after[k]):
            found.append(Effect(OFF_TABLE, k))
            continue
        tilt = tilt_deg(before[k], after[k])
        if slot_kind(name) == "block" and tilt > EFFECTS.block_tip_deg:
            found.append(Effect(BLOCK_TIPS, k))
        elif slot_kind(name) in ("cup", "support") and tilt > EFFECTS.topple_deg:
            found.append(Effect(TOPPLED, k))
        if np.linalg.norm(after[k, :2] - before[k, :2]) > EFFECTS.moved:
            host = slot_kind(slots[acted]) if acted is not None else ""
            found.append(Effect(_moved_kind(before, after, k, acted, held_after, host), k))
    return StepEffects(kind, acted, tuple(found))


def _moved_kind(
    before: np.ndarray, after: np.ndarray, k: int, acted: int | None, held_after: int, host_kind: str
) -> str:
    """Carried when it rode on the acted-on object and still does (or was lifted with it)."""
    if acted is None or not rested_on(before[k], before[acted], host_kind):
        return PUSHED
    if held_after == acted or (_present(after[acted]) and rested_on(after[k], after[acted], host_kind)):
        return CARRIED
    return PUSHED


def _tipped(pose: np.ndarray, limit_deg: float) -> bool:
    """Is the body's z axis more than `limit_deg` off vertical (either way up)?"""
    return float(np.degrees(np.arccos(min(1.0, abs(float(axis_up(pose)[2])))))) > limit_deg


def _placed(after: np.ndarray, k: int, action: np.ndarray, kind: str) -> list[Effect]:
    """The placed object: stays where it was put (no effect), slides, or falls."""
    if not _present(after):
        return [Effect(PLACED_FALLS, k)]
    target = action[Col.POSITION]
    # A ball's axis means nothing; its height alone says whether it fell.
    toppled = kind != "ball" and _tipped(after, EFFECTS.topple_deg)
    if toppled or after[2] < target[2] - EFFECTS.drop:
        return [Effect(PLACED_FALLS, k)]
    effects = []
    if np.linalg.norm(after[:2] - target[:2]) > EFFECTS.moved:
        effects.append(Effect(PLACED_SLIDES, k))
    if kind == "block" and _tipped(after, EFFECTS.block_tip_deg):
        effects.append(Effect(BLOCK_TIPS, k))
    return effects


def label_steps(
    poses: np.ndarray, held: np.ndarray, actions: np.ndarray, slots: tuple[str, ...]
) -> list[StepEffects]:
    """Every execution of one sequence: its poses and held slots per state, its actions."""
    return [
        step_effects(poses[t], poses[t + 1], int(held[t]), int(held[t + 1]), actions[t], slots)
        for t in range(len(actions))
    ]


def sequence_effects(seq) -> list[StepEffects]:
    """Every execution of a format.Sequence, labelled."""
    return label_steps(seq.poses, seq.held, seq.actions, seq.slots)


def summary_effects(summary: dict[str, np.ndarray], slots: tuple[str, ...]) -> list[list[StepEffects]]:
    """Every execution of a shard, labelled from its small arrays (format.shard_summary): one
    list per sequence."""
    out = []
    s0 = 0
    for k, n in enumerate(summary["state_count"]):
        actions = summary["actions"][s0 - k : s0 - k + n - 1]  # a sequence of n states has n - 1
        out.append(label_steps(summary["poses"][s0 : s0 + n], summary["held"][s0 : s0 + n], actions, slots))
        s0 += n
    return out


# ---------------------------------------------------------------------------- in the image
def disks(points: list[np.ndarray], radius: float = RADIUS_PX, size: int = SIZE) -> np.ndarray:
    """(size, size) bool: pixels within `radius` of any world point's projection."""
    mask = np.zeros((size, size), bool)
    if not points:
        return mask
    px = world_to_pixel(np.asarray(points, dtype=float))
    rows, cols = np.mgrid[0:size, 0:size]
    for col, row in px:
        mask |= (cols + 0.5 - col) ** 2 + (rows + 0.5 - row) ** 2 <= radius**2
    return mask


def object_mask(before: np.ndarray, after: np.ndarray, slots: list[int]) -> np.ndarray:
    """Disks around each slot at its position before and after (where it is on the table)."""
    points = [p[k, :3] for k in slots for p in (before, after) if not np.isnan(p[k, 0])]
    return disks(points)


def effect_points(
    effects: list[Effect], before: np.ndarray, after: np.ndarray, place_point
) -> tuple[list[np.ndarray], list[np.ndarray]]:
    """Where the affected objects were and where they ended, each a list of world points (an
    object not on the table has none). A placed object that slid or fell is looked for where it
    was put (before, it was in the gripper, and its leaving the gripper is the canonical part)."""
    starts, ends = [], []
    for e in effects:
        start = place_point if e.kind in (PLACED_SLIDES, PLACED_FALLS) else before[e.slot, :3]
        starts += [] if np.isnan(start[0]) else [start]
        ends += [] if np.isnan(after[e.slot, 0]) else [after[e.slot, :3]]
    return starts, ends


def effect_mask(effects: list[Effect], before: np.ndarray, after: np.ndarray, place_point) -> np.ndarray:
    """Where side effects show: disks around each affected object before and after
    (`effect_points`)."""
    starts, ends = effect_points(effects, before, after, place_point)
    return disks(starts + ends)


def landing_mask(effects: list[Effect], before: np.ndarray, after: np.ndarray, place_point) -> np.ndarray:
    """The part of `effect_mask` where affected objects land: their end disks outside every
    start disk. The rest is where they leave from."""
    starts, ends = effect_points(effects, before, after, place_point)
    return disks(ends) & ~disks(starts)


def step_mask(step: StepEffects, before: np.ndarray, after: np.ndarray, action: np.ndarray) -> np.ndarray:
    """Where one execution's side effects show (all False for a canonical step)."""
    return effect_mask(list(step.effects), before, after, np.asarray(action[Col.POSITION], dtype=float))
