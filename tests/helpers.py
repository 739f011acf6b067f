"""What several test files share: a toy world model whose goal lies deep, and a small task.

(Scripted simulator scenes are in `scenarios.py`.)
"""

import numpy as np

from afford.planning.tree import WorldModel
from afford.sim.affordance import Affordance, Detection

CELLS = 24
GOAL_CELL = 12  # six steps of +2 from cell 0


def bar(p: int) -> np.ndarray:
    """A (4, CELLS, 4) image filled from cell 0 up to cell p: nearer cells look nearer."""
    img = np.zeros((4, CELLS, 4), dtype=np.float32)
    img[:, : p + 1] = 1.0
    return img


class StepWorld(WorldModel):
    """State p; a grasp at q moves to q, for q in p-2 .. p+2 (five edges a node)."""

    def root(self):
        return bar(0), 0

    def recognise(self, nodes):
        return [
            [
                Detection(Affordance("grasp", (float(q), 0.0, 0.0), 0.0, False))
                for q in range(n.state - 2, n.state + 3)
            ]
            for n in nodes
        ]

    def predict(self, parents, actions):
        out = []
        for a in actions:
            q = int(a.position[0])
            out.append((bar(q), q) if 0 <= q < CELLS else None)
        return out


# A task of two steps on a real scene: the cup goes onto the support.
GOOD = {
    "format": 1,
    "name": "toy",
    "scene": {
        "objects": [{"kind": "cup", "pos": [0.0, 0.3, 0.0425]}, {"kind": "support", "pos": [0.1, 0.3, 0.03]}]
    },
    "goal": {
        "type": "positive",
        "scene": {
            "objects": [
                {"kind": "cup", "pos": [0.1, 0.3, 0.1025]},
                {"kind": "support", "pos": [0.1, 0.3, 0.03]},
            ]
        },
        "crop": {"centre": [0.1, 0.3, 0.06], "size": [16, 16]},
    },
    "max_steps": 2,
    "success": {"on": {"object": "cup0", "host": "support0"}},
}
