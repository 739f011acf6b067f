"""How much of each object the camera shows, read from a dataset's instance masks (`--masks`).

The paper captures its states top-down "to minimise occlusion" (III.B): what decides an
outcome (a support under the block, a cup behind another) should show in the image that a
net reads. This counts, per kind, the present objects that show fewer than
`VISIBILITY.min_pixels` pixels, and what covers each: the object seen where its centre
projects.
"""

from __future__ import annotations

from collections import Counter
from dataclasses import dataclass, field

import numpy as np

from afford.data.effects import slot_kind
from afford.sim import camera as cam
from afford.sim.constants import KINDS, VISIBILITY

NOTHING = "nothing"  # the arm, or an object beyond the view's edge: no slot is seen there


@dataclass
class Visibility:
    """Per kind: present (on the table, not held) object-states, those showing fewer than
    `min_pixels`, and what covered those (a kind, or NOTHING)."""

    min_pixels: int = VISIBILITY.min_pixels
    present: Counter[str] = field(default_factory=Counter)
    hidden: Counter[str] = field(default_factory=Counter)
    covered_by: dict[str, Counter[str]] = field(default_factory=dict)

    def add(self, masks: np.ndarray, poses: np.ndarray, held: np.ndarray, slots: tuple[str, ...]) -> None:
        """States of a shard: masks (T, H, W) of slot indices, poses (T, slots, 7), held (T,)."""
        kinds = [slot_kind(name) for name in slots]
        for t in range(len(masks)):
            counts = np.bincount(masks[t].ravel().astype(np.int64) + 1, minlength=len(slots) + 1)[1:]
            for k, kind in enumerate(kinds):
                if np.isnan(poses[t, k, 0]) or held[t] == k:
                    continue
                self.present[kind] += 1
                if counts[k] >= self.min_pixels:
                    continue
                self.hidden[kind] += 1
                self.covered_by.setdefault(kind, Counter())[_cover(masks[t], poses[t, k, :3], k, kinds)] += 1

    def share(self, kind: str) -> float:
        return self.hidden[kind] / max(self.present[kind], 1)

    def as_dict(self) -> dict:
        return {
            "min_pixels": self.min_pixels,
            "per_kind": {
                kind: {
                    "present": self.present[kind],
                    "hidden": self.hidden[kind],
                    "share": round(self.share(kind), 4),
                    "covered_by": dict(self.covered_by.get(kind, Counter()).most_common()),
                }
                for kind in KINDS
                if self.present[kind]
            },
        }


def _cover(mask: np.ndarray, centre: np.ndarray, k: int, kinds: list[str]) -> str:
    """The kind seen most within 4 px of where the object's centre projects (itself aside)."""
    row, col = cam.pixel_index(centre)
    window = mask[max(row - 4, 0) : row + 5, max(col - 4, 0) : col + 5].ravel()
    seen = window[(window >= 0) & (window != k)]
    if not len(seen):
        return NOTHING
    return kinds[int(np.bincount(seen).argmax())]
