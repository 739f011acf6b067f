"""How each step of a generated sequence picks the affordance it executes.

The paper draws every execution at random from the list of what the scene affords (III.B):
`uniform`. Side effects then follow in about one execution of nine, and a prediction net
sees few of each kind. `effects` is an option of our own, kept apart from the paper's
distribution and named in the dataset's manifest: each step tries executions in random order,
putting the scene back after each, and keeps the first that had a side effect
(`data/effects.py`, labelled from true poses); where none of the tries had one it keeps the
last, an execution drawn as the paper draws. Most states afford no side effect at all (a cup
alone on the table), so the sequences still hold canonical steps in every arrangement: on 25
sequences, 40% of the executions had a side effect against 14% drawn uniformly, at 2.3 times
the simulation.

A draw gets the scene, the candidates (turns parametrised) and the sequence's generator, and
returns the executed affordance with the scene left in the state after it (None: none of the
candidates could be carried out), and how many drawn executions the arm could not carry out.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from afford.data.effects import step_effects
from afford.sim.affordance import encode_affordance

# `effects`: how many executions a step tries before it settles for one without a side effect
# (each try costs a simulated execution).
SEEK_TRIES = 12


def pose_array(scene) -> np.ndarray:
    """(slots, 7) every object's position and quaternion; NaN rows: not on the table."""
    rows = []
    for o in scene.objects(present_only=False):
        rows.append(np.concatenate([o.pos, o.quat]) if o.present else np.full(7, np.nan))
    return np.array(rows, dtype=np.float32)


def _held_slot(scene, slots: tuple[str, ...]) -> int:
    return slots.index(scene.held) if scene.held else -1


def draw_uniform(scene, candidates: list, rng: np.random.Generator) -> tuple[object | None, int]:
    """The paper's: one at random; one the arm cannot carry out is undone and another drawn."""
    failed = 0
    while candidates:
        a = candidates.pop(int(rng.integers(len(candidates))))
        snap = scene.snapshot()
        if scene.execute(a).executed:
            return a, failed
        failed += 1
        scene.restore(snap)
    return None, failed


def draw_seeking_effects(scene, candidates: list, rng: np.random.Generator) -> tuple[object | None, int]:
    """The first of up to SEEK_TRIES executions with a side effect, else the last tried."""
    slots = tuple(name for name, _ in scene.slots)
    start = scene.snapshot()
    before, held_before = pose_array(scene), _held_slot(scene, slots)
    failed = tries = 0
    kept = None
    while candidates and tries < SEEK_TRIES:
        a, f = draw_uniform(scene, candidates, rng)
        failed += f
        if a is None:
            break
        tries += 1
        kept = a
        fx = step_effects(
            before, pose_array(scene), held_before, _held_slot(scene, slots), encode_affordance(a), slots
        )
        if not fx.canonical or tries == SEEK_TRIES or not candidates:
            return a, failed
        scene.restore(start)
    if kept is not None:  # the last try was undone when the candidates ran out: carry it out again
        scene.restore(start)
        scene.execute(kept)
    return kept, failed


DRAWS: dict[str, Callable] = {"uniform": draw_uniform, "effects": draw_seeking_effects}
