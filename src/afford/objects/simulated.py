"""A world model that separates the costs: the simulator run from perceived objects.

The oracle plans with the true state and true physics; the object world model with a perceived
state and learned dynamics. This one takes the perceived state and the true physics: it builds
a simulator scene from the objects perception sees in the start image and executes each
affordance there. Beside the other two it tells what perception costs (oracle against this) and
what learned dynamics cost (this against the object world model).
"""

from __future__ import annotations

import numpy as np

from afford.objects.dynamics import ObjectOutcomes
from afford.objects.state import KINDS, N_SLOTS, SLOT_KIND
from afford.sim.affordance import decode_affordance
from afford.sim.scene import ObjectSpec, Scene


def scene_from_state(scene: Scene, poses: np.ndarray, held: int) -> None:
    """Put the objects of a state (pose rows per slot, NaN: none; the held slot or -1) into
    `scene`, the held one welded in the gripper, and let them settle: an object perceived a
    little above its support comes to rest on it."""
    specs, names, counts = [], {}, dict.fromkeys(KINDS, 0)
    for slot in range(N_SLOTS):
        if np.isnan(poses[slot, 0]):
            continue
        kind = KINDS[SLOT_KIND[slot]]
        q = np.asarray(poses[slot, 3:7], dtype=float)
        specs.append(ObjectSpec(kind, tuple(float(v) for v in poses[slot, :3]), tuple(q / np.linalg.norm(q))))
        names[slot] = f"{kind}{counts[kind]}"
        counts[kind] += 1
    scene.reset(specs, settle=False, check=False)
    if held >= 0 and held in names:
        scene.attach(names[held])
    scene.settle()


def simulate(scene: Scene, before: np.ndarray, held: np.ndarray, actions: np.ndarray) -> ObjectOutcomes:
    """The next state of N executions, each run in `scene` from its start state: one outcome of
    probability 1 (an execution the arm cannot carry out leaves the state as it was)."""
    from afford.data.draws import pose_array

    slots = [name for name, _ in scene.slots]
    poses = np.array(before, dtype=np.float32, copy=True)
    held_next = np.array(held, copy=True)
    for i in range(len(actions)):
        scene_from_state(scene, before[i], int(held[i]))
        if scene.execute(decode_affordance(actions[i])).executed:
            # The scene names objects by kind in order; the state's slots may have gaps.
            order = [s for s in range(N_SLOTS) if not np.isnan(before[i, s, 0])]
            after, named = pose_array(scene), {}
            counts = dict.fromkeys(KINDS, 0)
            for s in order:
                kind = KINDS[SLOT_KIND[s]]
                named[s] = slots.index(f"{kind}{counts[kind]}")
                counts[kind] += 1
            poses[i] = np.nan
            for s, row in named.items():
                poses[i, s] = after[row]
            inverse = {row: s for s, row in named.items()}
            held_next[i] = inverse.get(slots.index(scene.held), -1) if scene.held else -1
    return ObjectOutcomes(poses[:, None], held_next[:, None], np.ones((len(actions), 1)))
