"""Planning over every outcome the net foresees: a plan scored by its expected eq. (5).

A prediction net with two outcomes per step (a canonical one and a side effect, with a head
that says how likely each is; prediction/model.py) is used by the learned planner as one:
each step carries on the likelier outcome, and a side effect the head gives 40% is planned
as if it never happens. This world model keeps the alternatives instead. Each state of the
tree is a small set of branches, each with its own latent, memory trace and image and the
probability of the outcomes that led to it; every action steps every branch, and each branch
splits into the net's outcomes. A plan then scores the expected eq. (5) over its branches,
so a plan whose side effect would spoil the goal one time in three pays a third of that, and
a plan that needs a side effect to happen gets the credit of how likely it is (paper V: "a
more principled approach" to actions with uncertain outcomes). The branches are a mixture with
a spread of their own, so a plan may also pay for how unsure its outcome is (`risk`).

Branches less likely than `OUTCOME_FLOOR` are dropped and at most `MOST_BRANCHES` kept per
state (the likeliest), so a tree costs at most that many times the one-outcome search, and in
practice little more: most steps' side effects are given a few percent. Recognition runs on
the likeliest branch's image, which is also the state's picture.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import torch

from afford.images import to_chw, to_hwc
from afford.planning.goal import Goal
from afford.planning.learned import LearnedModel
from afford.planning.tree import Node, Scores
from afford.sim.affordance import encode_affordance
from afford.sim.affordances import Affordance

OUTCOME_FLOOR = 0.05  # a branch less likely than this is dropped (the rest renormalised)
MOST_BRANCHES = 4  # the likeliest branches a state keeps
CHUNK = 256  # branches stepped in one call of the net


@dataclass
class Branches:
    """A state's alternatives: their probabilities (n,), summing to 1, likeliest first, and
    each one's latent, memory trace (n, ...) and image (n, H, W, C)."""

    probability: np.ndarray
    latent: torch.Tensor
    memory: torch.Tensor
    images: np.ndarray


def keep(probability: np.ndarray, floor: float = OUTCOME_FLOOR, most: int = MOST_BRANCHES) -> np.ndarray:
    """The indices of the branches kept, likeliest first: at most `most`, none below `floor`
    (the likeliest always)."""
    order = np.argsort(-probability, kind="stable")[:most]
    return order[(probability[order] >= floor) | (np.arange(len(order)) == 0)]


class BranchingModel(LearnedModel):
    """The learned world model (`LearnedModel`) with every foreseen outcome kept as a branch.

    `risk`: a state scores its expected eq. (5) plus this many standard deviations of eq. (5)
    over its branches (the mixture's), minus for a negative goal: of two plans expected equally
    close, the one whose outcome the net is sure of wins. 0: the expected loss alone."""

    def __init__(self, image, recognizer, predictor, risk: float = 0.0):
        super().__init__(image, recognizer, predictor)
        self.risk = risk

    @torch.no_grad()
    def root(self):
        image, state = super().root()
        return image, Branches(np.ones(1), state.latent[None], state.memory[None], image[None])

    @torch.no_grad()
    def predict(self, parents: list[Node], actions: list[Affordance]):
        owner = np.concatenate([np.full(len(p.state.probability), k) for k, p in enumerate(parents)])
        rows = torch.from_numpy(np.stack([encode_affordance(actions[k]) for k in owner]))
        latent = torch.cat([p.state.latent for p in parents])
        memory = torch.cat([p.state.memory for p in parents])
        image = to_chw(np.concatenate([p.state.images for p in parents]))
        parts = [
            self.net.step_outcomes(latent[at], memory[at], image[at], rows[at])
            for at in torch.arange(len(rows)).split(CHUNK)
        ]  # in chunks: every parent may bring several branches, each drawn K times
        self.p_steps += len(owner)
        prior = np.concatenate([p.state.probability for p in parents])
        drawn = torch.cat([o.probability for o in parts]).numpy()
        probability = (prior[:, None] * drawn).reshape(-1)  # (branches * K,)
        k = drawn.shape[1]
        latent = torch.cat([o.latent for o in parts]).flatten(0, 1)
        memory = torch.cat([o.memory for o in parts]).flatten(0, 1)
        images = np.concatenate([to_hwc(o.images.flatten(0, 1)) for o in parts])
        owner = np.repeat(owner, k)
        children = []
        for j in range(len(parents)):
            mine = np.flatnonzero(owner == j)
            kept = mine[keep(probability[mine] / probability[mine].sum())]
            p = probability[kept] / probability[kept].sum()
            at = torch.from_numpy(kept)
            children.append((images[kept[0]], Branches(p, latent[at], memory[at], images[kept])))
        return children

    def score(self, goal: Goal, nodes: list[Node]) -> Scores:
        return risky_scores(goal, [n.state for n in nodes], self.risk)


def risky_scores(goal: Goal, states: list, risk: float) -> Scores:
    """Each state's expected eq. (5) over its branches (states with `probability` and
    `images`), `risk` standard deviations of it added (taken, for a negative goal), and that
    deviation."""
    mean, variance = branch_moments(goal, states)
    std = np.sqrt(variance)
    return Scores(mean + (-risk if goal.negative else risk) * std, std)


def branch_moments(goal: Goal, states: list[Branches]) -> tuple[np.ndarray, np.ndarray]:
    """Per state, the mean and variance of eq. (5) over its branches, each weighed by its
    probability: the mixture's moments."""
    losses = goal.loss(np.concatenate([s.images for s in states]))
    sizes = np.array([len(s.probability) for s in states])
    ends = np.cumsum(sizes)
    mean, variance = np.zeros(len(states)), np.zeros(len(states))
    for i, (s, a, b) in enumerate(zip(states, ends - sizes, ends, strict=True)):
        mean[i] = s.probability @ losses[a:b]
        variance[i] = s.probability @ (losses[a:b] - mean[i]) ** 2
    return mean, variance
