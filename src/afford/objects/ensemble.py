"""Several dynamics nets trained apart, judged together (paper V: "a more principled approach"
to outcomes a single net is unsure of).

Two dynamics nets of one recipe trained from different seeds put a pushed or toppled object
half a pixel apart in median and win or lose different tasks (docs/experiments/objects-dynamics.md):
each net's error is partly its own. Fusing the members' predictions object by object keeps
what they agree on and cancels part of what each gets wrong on its own:

- each member's outcomes are ranked likeliest first, and the r-th outcome of every member is
  fused into the ensemble's r-th outcome, with the members' mean probability;
- per object, the members vote: if most say something happens to it (it leaves the table or
  moves; an object a member calls still is its start row exactly, `state.moved`), it is gone
  where more of those say gone than moved, else moved; otherwise it is copied exactly, as
  eq. (2) on objects copies a still object;
- a moved object lands at the median of the movers' positions (a median, since one member's
  stray landing should not drag the others'), with the axes of the mover nearest that point;
- the held slot is the members' most common answer, none where the fused poses put that
  object off the table.

`DynamicsEnsemble.outcomes` answers what `ObjectDynamics.outcomes` does, so every part of the
object world model (planning, rollouts, `afford eval dynamics`) takes either.
"""

from __future__ import annotations

import warnings
from collections.abc import Sequence

import numpy as np

from afford.objects.dynamics import ObjectDynamics, Outcomes
from afford.objects.state import moved


class DynamicsEnsemble:
    """Dynamics nets trained apart (the first is the folder's own), fused object by object."""

    def __init__(self, members: Sequence[ObjectDynamics]):
        if not members:
            raise ValueError("an ensemble needs at least one dynamics net")
        outcomes = {m.config.outcomes for m in members}
        if len(outcomes) > 1:
            raise ValueError(f"the members foresee different numbers of outcomes: {sorted(outcomes)}")
        self.members = tuple(members)

    def __len__(self) -> int:
        return len(self.members)

    def outcomes(
        self, before: np.ndarray, held: np.ndarray, actions: np.ndarray, paths: np.ndarray | None = None
    ) -> Outcomes:
        return fuse([m.outcomes(before, held, actions, paths) for m in self.members], before)


# What a world model's dynamics may be: one net or several judged together.
Dynamics = ObjectDynamics | DynamicsEnsemble


def by_likelihood(outcomes: Outcomes) -> Outcomes:
    """The same outcomes, each execution's ordered likeliest first."""
    order = np.argsort(-outcomes.probability, axis=1, kind="stable")
    rows = np.arange(len(order))[:, None]
    return Outcomes(
        outcomes.poses[rows, order], outcomes.held[rows, order], outcomes.probability[rows, order]
    )


def fuse(members: Sequence[Outcomes], before: np.ndarray) -> Outcomes:
    """One set of K outcomes from M members' (see the module's docstring); `before` (N, slots, 7)
    are the start states every member predicted from."""
    ranked = [by_likelihood(o) for o in members]
    poses = np.stack([o.poses for o in ranked])  # (M, N, K, slots, 7)
    m = len(ranked)
    start = np.broadcast_to(before[None, :, None], poses.shape)
    gone = np.isnan(poses[..., 0])
    movers = moved(start, poses) & ~gone
    happens = 2 * (gone | movers).sum(0) > m
    gone_vote = happens & (gone.sum(0) > movers.sum(0))
    move_vote = happens & ~gone_vote
    position = np.where(movers[..., None], poses[..., :3], np.nan)
    with warnings.catch_warnings():  # an object no member moved has an all-NaN median
        warnings.simplefilter("ignore", RuntimeWarning)
        centre = np.nanmedian(position, axis=0)  # (N, K, slots, 3); NaN where no member moved it
    distance = np.linalg.norm(np.nan_to_num(position - centre[None], nan=np.inf), axis=-1)
    nearest = np.where(movers, distance, np.inf).argmin(0)
    axes = np.take_along_axis(poses[..., 3:7], nearest[None, ..., None], axis=0)[0]
    fused = np.repeat(before[:, None], poses.shape[2], axis=1).astype(poses.dtype)
    fused[..., :3] = np.where(move_vote[..., None], centre, fused[..., :3])
    fused[..., 3:7] = np.where(move_vote[..., None], axes, fused[..., 3:7])
    fused[gone_vote] = np.nan
    held = _most_common(np.stack([o.held for o in ranked]))  # (N, K)
    slot_gone = np.take_along_axis(gone_vote, np.maximum(held, 0)[..., None], axis=-1)[..., 0]
    held = np.where(slot_gone, -1, held)
    return Outcomes(fused, held, np.mean([o.probability for o in ranked], axis=0))


def _most_common(values: np.ndarray) -> np.ndarray:
    """(M, ...) integers from -1 -> (...) the most common along the first axis (ties: the smallest)."""
    shifted = values + 1
    counts = np.stack([(shifted == v).sum(0) for v in range(int(shifted.max()) + 1)])
    return counts.argmax(0) - 1
