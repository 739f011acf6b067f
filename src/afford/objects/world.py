"""The object world model's state and its one step, shared by the planner's world model
(`planning/objects_model.py`) and the rollout the evaluations measure (`rollout.py`).

A state is the objects in their slots, the rendering of them that the next drawing is compared
with, and which objects the image still shows as perception saw them in the start image. A step
takes the objects where the dynamics put them, rests a moved object that sank into what it
landed on (`Drawer.rest`), renders them and draws the next image over the last (eq. 3 on
objects: only the pixels of what moved, and where a moved object was seen, change).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from afford.objects.draw import Drawer
from afford.objects.perceive import perceive, slot_masks, to_state
from afford.objects.perception import PerceptionNet
from afford.objects.state import moved


@dataclass
class ObjectState:
    """The objects of one state: pose rows per slot (NaN: none), the held slot (-1: none), their
    rendering, the pixels each slot's object was seen in in the start image (slots, H, W; one
    array for every state grown from that start), and which slots' objects the image still
    shows as seen there (not yet moved, so not yet redrawn)."""

    poses: np.ndarray
    held: int
    drawn: np.ndarray
    seen: np.ndarray
    as_seen: np.ndarray


def perceived(perception: PerceptionNet, drawer: Drawer, images: np.ndarray) -> list[ObjectState]:
    """The start state of each of (B, H, W, 4) images: the objects perception sees in it."""
    states = []
    for objects in perceive(perception, images):
        poses, held = to_state(objects)
        states.append(given(drawer, poses, held, slot_masks(objects)))
    return states


def given(drawer: Drawer, poses: np.ndarray, held: int, seen: np.ndarray) -> ObjectState:
    """A start state of objects known otherwise (the simulator's, `--planner objects-true`):
    pose rows, the held slot and the pixels each slot's object shows in the image (slots, H,
    W), or the image's instance mask (slot per pixel, -1: none)."""
    poses = np.asarray(poses, np.float32)
    if seen.ndim == 2:
        seen = np.stack([seen == slot for slot in range(len(poses))])
    return ObjectState(poses, int(held), drawer.render(poses, int(held)), seen, seen.any((1, 2)))


def step(
    drawer: Drawer, image: np.ndarray, state: ObjectState, poses: np.ndarray, held: int
) -> tuple[np.ndarray, ObjectState]:
    """The next image and state when the objects of `state`, drawn in `image`, go where the
    dynamics put them (`poses`, the held slot `held`)."""
    go = moved(state.poses, poses)
    poses = drawer.rest(poses, held, go)
    drawn = drawer.render(poses, held)
    image = drawer.draw(image, state.drawn, drawn, state.seen[go & state.as_seen].any(0))
    return image, ObjectState(poses, held, drawn, state.seen, state.as_seen & ~go)
