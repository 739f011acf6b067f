"""The affordance types, one registry (paper II.A): for each, when it can be commenced, where
the detector looks for it, what the gripper does there, its canonical effect (the symbolic
baseline's model), its execution parameters and how pictures draw it.

Each type lives in its own module and registers itself (`base.register`); the registration order is the type's
index in the data (`format.Col.TYPE`), so new types go last. A fourth type is its module plus
its line at the bottom of this file.
"""

from __future__ import annotations

# The type modules register themselves as they are imported: this order is the type index.
from afford.sim.affordance_types import grasp, place, turn  # noqa: F401

# The record and the registry sit in `base`, which the type modules import, so nothing
# imports back up into this file.
from afford.sim.affordance_types.base import (  # noqa: F401
    REGISTRY,
    AffordanceType,
    register,
    type_index,
    type_name,
)

TYPES = tuple(REGISTRY)
