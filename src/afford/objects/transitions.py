"""Every execution of a dataset as a transition: the objects before, the affordance, the
objects after. Read from the shards' small arrays, never their images, so a dataset
made with `afford generate --poses-only` serves as well as one with images."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from afford.data.effects import StepEffects, step_effects
from afford.data.format import DataError, Dataset, shard_path, shard_summary
from afford.objects.state import SLOTS
from afford.sim.affordance import AFF_WIDTH


@dataclass
class Transitions:
    """N executions: poses (N, slots, 7) before and after, held slots before and after (-1:
    none), the executed affordance rows (N, 7), and which sequence and step each came from."""

    before: np.ndarray
    after: np.ndarray
    held_before: np.ndarray
    held_after: np.ndarray
    actions: np.ndarray
    sequence: np.ndarray
    step: np.ndarray  # which execution of its sequence (its start is state `step`)

    def __len__(self) -> int:
        return len(self.actions)

    def subset(self, keep: np.ndarray) -> Transitions:
        return Transitions(**{k: v[keep] for k, v in vars(self).items()})

    @staticmethod
    def concatenate(parts: list[Transitions]) -> Transitions:
        return Transitions(**{k: np.concatenate([getattr(p, k) for p in parts]) for k in vars(parts[0])})

    def effects(self) -> list[StepEffects]:
        """Each execution labelled (data/effects.py): acted-on slot and side effects."""
        slots = tuple(name for name, _ in SLOTS)
        return [
            step_effects(
                self.before[i],
                self.after[i],
                int(self.held_before[i]),
                int(self.held_after[i]),
                self.actions[i],
                slots,
            )
            for i in range(len(self))
        ]


def read_transitions(root: str | Path, split: str | None = None, limit: int | None = None) -> Transitions:
    """The executions of `split` (None: every sequence) of the dataset at `root`; at most the
    split's first `limit` sequences."""
    data = Dataset(root)
    if tuple(data.slots) != tuple(name for name, _ in SLOTS):
        raise DataError(f"{root}: its object slots {data.slots} are not this afford's")
    wanted = data.indices(split)
    if limit is not None:
        wanted = range(wanted.start, min(wanted.stop, wanted.start + limit))
    shards = sorted({i // data.manifest.shard_size for i in wanted})
    parts: dict[str, list[np.ndarray]] = {k: [] for k in Transitions.__dataclass_fields__}
    for k in shards:
        z = shard_summary(shard_path(data.root, k))
        s0 = 0
        for j, n in enumerate(z["state_count"]):
            index = int(z["index"][j])
            e0 = s0 - j  # this sequence's first execution row
            if index in wanted and n > 1:
                states = slice(s0, s0 + n)
                poses, held = z["poses"][states], z["held"][states]
                parts["before"].append(poses[:-1])
                parts["after"].append(poses[1:])
                parts["held_before"].append(held[:-1])
                parts["held_after"].append(held[1:])
                parts["actions"].append(z["actions"][e0 : e0 + n - 1])
                parts["sequence"].append(np.full(n - 1, index))
                parts["step"].append(np.arange(n - 1))
            s0 += n
    if not parts["actions"]:
        return Transitions(
            np.zeros((0, len(SLOTS), 7), np.float32),
            np.zeros((0, len(SLOTS), 7), np.float32),
            np.zeros(0, np.int8),
            np.zeros(0, np.int8),
            np.zeros((0, AFF_WIDTH), np.float32),
            np.zeros(0, np.int64),
            np.zeros(0, np.int64),
        )
    return Transitions(**{k: np.concatenate(v) for k, v in parts.items()})
