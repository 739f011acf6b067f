"""What rests on what, asked of a live scene: a physical query that the success predicates,
the symbolic planner and the perturbed starts share.

(`data/effects.py` asks the same of stored poses, where no scene is at hand: there an object
rode on another when it stood above its centre and over its top face.)
"""

from __future__ import annotations

import mujoco
import numpy as np

from afford.sim.constants import BLOCK, SUPPORT

ON_GAP = (-0.012, 0.02)  # metres between the object's lowest point and the host's top
ON_MARGIN = 0.01  # the object's centre may overhang the host's top face by this much
HOST_HALF = {"support": SUPPORT.half, "block": BLOCK.half}  # what can hold another object


def rests_on(scene, name: str, host: str) -> bool:
    """Does object `name` rest on the top of `host` (a support, the block, or "table")?"""
    o = scene.object(name)
    if not o.present or o.held:
        return False
    low = scene.lowest_point(o.name)
    if host == "table":
        return bool(low < ON_GAP[1])
    h = scene.object(host)
    if not h.present or h.held or h.kind not in HOST_HALF:
        return False
    top = scene.highest_point(host)
    if not ON_GAP[0] <= low - top <= ON_GAP[1]:
        return False
    rot = np.zeros(9)
    mujoco.mju_quat2Mat(rot, h.quat)
    local = rot.reshape(3, 3).T @ (o.pos - h.pos)
    half = HOST_HALF[h.kind]
    return bool(abs(local[0]) <= half[0] + ON_MARGIN and abs(local[1]) <= half[1] + ON_MARGIN)
