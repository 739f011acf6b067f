"""Planning with an ensemble of prediction nets: risk-averse plan scores (paper V).

The ensemble world model grows the same tree as the learned one (recognition on the real
start and on predicted states, prediction by EM*D), but every member of the ensemble rolls
out its own chain, so each state of the tree is K predicted images. Recognition runs on their
mean; eq. (5) is computed on each, and a plan scores the members' mean loss plus `risk` times
its standard deviation over the members: of two plans predicted equally close to the goal,
the one the members agree on wins. For a negative goal (eq. (4) takes the greatest loss) the
spread counts the other way: a state sure to be far from the goal beats one that may not be.
With risk 0 the score is the members' mean loss, the ensemble without caution.

Members that foresee two outcomes per step (a canonical one and a side effect, with a head
that says how likely each is) may also keep both (`EnsembleBranchingModel`, `--outcomes
expected`): each member then holds its own branches (planning/branches.py), its loss is their
mixture's mean and variance, and the plan's moments are again the members' combined so.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import torch

from afford.errors import UserError
from afford.images import to_chw, to_hwc
from afford.planning.branches import Branches, BranchingModel, branch_moments
from afford.planning.goal import Goal
from afford.planning.learned import recognise_nodes
from afford.planning.tree import Node, Recognised, Scores, WorldModel
from afford.prediction.ensemble import spread
from afford.prediction.model import PredictionNet
from afford.recognition.infer import Recognizer
from afford.sim.affordance import encode_affordance
from afford.sim.affordances import Affordance

RISK = 1.0  # the ensemble planner's default weight on the spread of a plan's outcome


class EnsembleError(UserError):
    """An ensemble planner without an ensemble; the message says where members go."""


@dataclass
class EnsembleState:
    """Each member's own state: its latent and memory trace (a tuple of K: members' latents may
    differ in width), and the images stacked on a first axis of K."""

    latent: tuple[torch.Tensor, ...]
    memory: tuple[torch.Tensor, ...]
    images: np.ndarray  # (K, H, W, C): each member's predicted image

    @property
    def pixel_spread(self) -> np.ndarray:
        """(H, W): the per-pixel standard deviation of the state: the members' spread
        (`prediction.ensemble.spread`)."""
        return spread(self.images)


def risk_score(
    losses: np.ndarray, risk: float, negative: bool, within: np.ndarray | None = None
) -> tuple[np.ndarray, np.ndarray]:
    """(score, spread) per state from the members' eq. (5) losses (K, B), and `within` (K, B)
    each member's own variance of its loss (over its branches): the mean plus (a positive goal)
    or minus (a negative one) `risk` standard deviations, the variance being the members' mean
    variance plus the variance of their means."""
    mean = losses.mean(axis=0)
    variance = losses.var(axis=0) + (0.0 if within is None else within.mean(axis=0))
    std = np.sqrt(variance)
    return mean + (-risk if negative else risk) * std, std


class EnsembleModel(WorldModel):
    """A `WorldModel` of the recognizer and K prediction nets, from the real start image."""

    def __init__(
        self, image: np.ndarray, recognizer: Recognizer, members: tuple[PredictionNet, ...], risk: float
    ):
        if len(members) < 2:
            raise EnsembleError(
                f"an ensemble needs at least 2 prediction nets, not "
                f"{len(members)}: put the members in the weights folder's ensemble/ (`afford weights "
                "export ensemble/NAME.safetensors`), beside its prediction net"
            )
        self.image = np.asarray(image, dtype=np.float32)
        self.recognizer = recognizer
        self.members = tuple(m.eval() for m in members)
        self.risk = risk
        self.p_steps = 0

    @torch.no_grad()
    def root(self):
        x = to_chw(self.image[None])
        states = [m.encode(x) for m in self.members]
        latent = tuple(s[0][0] for s in states)
        memory = tuple(s[1][0] for s in states)
        images = np.repeat(self.image[None], len(self.members), axis=0)
        return self.image, EnsembleState(latent, memory, images)

    def recognise(self, nodes: list[Node]) -> list[Recognised]:
        return recognise_nodes(self.recognizer, nodes)

    @torch.no_grad()
    def predict(self, parents: list[Node], actions: list[Affordance]):
        rows = torch.from_numpy(np.stack([encode_affordance(a) for a in actions]))
        out_latent, out_memory, out_images = [], [], []
        for k, member in enumerate(self.members):
            latent = torch.stack([p.state.latent[k] for p in parents])
            memory = torch.stack([p.state.memory[k] for p in parents])
            image = to_chw(np.stack([p.state.images[k] for p in parents]))
            step = member.step_hypotheses(latent, memory, image, rows)
            out_latent.append(step.latent)
            out_memory.append(step.memory)
            out_images.append(to_hwc(step.image))
        self.p_steps += len(parents) * len(self.members)
        images = np.stack(out_images)  # (K, B, H, W, C)
        return [
            (
                images[:, j].mean(axis=0),
                EnsembleState(
                    tuple(t[j] for t in out_latent),
                    tuple(t[j] for t in out_memory),
                    images[:, j],
                ),
            )
            for j in range(len(parents))
        ]

    def score(self, goal: Goal, nodes: list[Node]) -> Scores:
        """Eq. (5) per member, then `risk_score`: the score and the standard deviation of the loss."""
        stacked = np.concatenate([n.state.images for n in nodes])  # (B*K, H, W, C), node-major
        losses = goal.loss(stacked).reshape(len(nodes), len(self.members)).T
        return Scores(*risk_score(losses, self.risk, goal.negative))


@dataclass
class _MemberView:
    """One member's part of an ensemble node, as a member's own `BranchingModel` reads it."""

    state: Branches


class EnsembleBranchingModel(WorldModel):
    """K prediction nets, each keeping every outcome it foresees as a branch: a state is K
    sets of branches. Recognition runs on the members' mean of their likeliest images; a plan
    scores the members' mean expected eq. (5) plus `risk` standard deviations, the variance
    the members' mean mixture variance plus the variance of their expected losses."""

    def __init__(
        self, image: np.ndarray, recognizer: Recognizer, members: tuple[PredictionNet, ...], risk: float
    ):
        if not members or (len(members) < 2 and members[0].config.outcomes.hypotheses < 2):
            raise EnsembleError(
                "an ensemble that keeps outcomes needs at least 2 prediction nets, or one that "
                "foresees two outcomes per step: put the members in the weights folder's ensemble/ "
                "(`afford weights export ensemble/NAME.safetensors`), beside its prediction net"
            )
        self.recognizer = recognizer
        self.models = [BranchingModel(image, recognizer, m) for m in members]
        self.risk = risk

    @property
    def p_steps(self) -> int:
        return sum(m.p_steps for m in self.models)

    def root(self):
        roots = [m.root() for m in self.models]
        return roots[0][0], tuple(state for _, state in roots)

    def recognise(self, nodes: list[Node]) -> list[Recognised]:
        return recognise_nodes(self.recognizer, nodes)

    def predict(self, parents: list[Node], actions: list[Affordance]):
        per_member = [
            model.predict([_MemberView(p.state[k]) for p in parents], actions)
            for k, model in enumerate(self.models)
        ]
        return [
            (np.mean([m[j][0] for m in per_member], axis=0), tuple(m[j][1] for m in per_member))
            for j in range(len(parents))
        ]

    def score(self, goal: Goal, nodes: list[Node]) -> Scores:
        moments = [branch_moments(goal, [n.state[k] for n in nodes]) for k in range(len(self.models))]
        means = np.stack([m for m, _ in moments])  # (K, B)
        within = np.stack([v for _, v in moments])
        return Scores(*risk_score(means, self.risk, goal.negative, within))
