"""Continuous turn angles by back-propagation through the prediction net (paper V).

Section V: "parameters such as the turn angle ... should be generalised to continuous values
... run-time optimisation of the parameters of selected affordances using a back-propagation
strategy". The simulator is not differentiable but the prediction net is: for a plan that
holds turns, the plan is rolled out through the net from the start image, its last state is
scored against the goal patch by eq. (5) (`Goal.loss_torch`), and gradient descent moves
every turn's angle at once. The angle is 180 tanh(u) of a free u, so it stays in
[-180, 180]; a few restarts from spread-out angles keep the descent out of the nearest
local minimum. It needs a prediction net trained on turns by any angle (`afford generate
--turn-angles continuous`): a net that only saw +-90 has learned nothing in between.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np
import torch

from afford.images import to_chw
from afford.planning.goal import Goal
from afford.planning.tree import Node, SearchResult
from afford.sim.affordance import Col, encode_affordance
from afford.sim.affordances import Affordance

RESTART_ANGLES = (-135.0, -45.0, 45.0, 135.0)  # starting points, one per quadrant
STEPS = 40  # gradient steps per restart
LR = 0.1  # Adam's step on u, where the angle is 180 tanh(u)


@dataclass
class TurnOptimisation:
    plan: tuple[Affordance, ...]  # the plan with its turns at the best angles found
    loss: float  # eq. (5) of its predicted last state
    start_loss: float  # the same for the plan as given
    curves: list[list[float]] = field(default_factory=list)  # eq. (5) per step, per restart


def optimise_turns(
    net,
    start: np.ndarray,
    plan: tuple[Affordance, ...],
    goal: Goal,
    restarts: tuple[float, ...] = RESTART_ANGLES,
    steps: int = STEPS,
    lr: float = LR,
) -> TurnOptimisation:
    """Every turn of `plan` at the angle that brings the predicted outcome closest to `goal`.

    `net`: anything with PredictionNet's `rollout(image (1, C, H, W), actions (1, L, 7))`.
    `start`: the (H, W, C) start image. Each restart sets all turns to one angle of
    `restarts`; the plan as given is scored too, and wins if nothing beats it."""
    turns = [i for i, a in enumerate(plan) if a.turn]
    image = to_chw(start[None])
    rows = torch.from_numpy(np.stack([encode_affordance(a) for a in plan]))[None]

    def outcome(angles: torch.Tensor) -> torch.Tensor:
        actions = rows.clone()
        actions[0, turns, Col.TURN] = angles
        return goal.loss_torch(net.rollout(image, actions)[:, -1])[0]

    with torch.no_grad():
        given = float(outcome(torch.tensor([plan[i].turn for i in turns], dtype=torch.float32)))
    best_loss, best_angles, curves = given, [plan[i].turn for i in turns], []
    if not turns:
        return TurnOptimisation(plan, given, given)
    # Only the angles learn: the net's own weights are held (and restored after).
    weights = [p for p in getattr(net, "parameters", list)() if p.requires_grad]
    for p in weights:
        p.requires_grad_(False)
    try:
        curves = _descend(outcome, len(turns), restarts, steps, lr)
    finally:
        for p in weights:
            p.requires_grad_(True)
    for curve, angles in curves:
        if curve and min(curve) < best_loss:
            best_loss, best_angles = min(curve), angles
    new = list(plan)
    for i, angle in zip(turns, best_angles, strict=True):
        new[i] = plan[i].with_turn(float(np.clip(angle, -180.0, 180.0)) or 1e-3)
    return TurnOptimisation(tuple(new), best_loss, given, [c for c, _ in curves])


def _descend(outcome, n: int, restarts, steps: int, lr: float) -> list[tuple[list[float], list[float]]]:
    """Per restart: eq. (5) at each step, and the angles where it was least."""
    out = []
    for angle in restarts:
        u = torch.full((n,), float(np.arctanh(angle / 180.0)), requires_grad=True)
        opt = torch.optim.Adam([u], lr=lr)
        curve, best, where = [], float("inf"), []
        for _ in range(steps):
            angles = 180.0 * torch.tanh(u)
            loss = outcome(angles)
            curve.append(float(loss.detach()))
            if curve[-1] < best:
                best, where = curve[-1], angles.detach().tolist()
            opt.zero_grad()
            loss.backward()
            opt.step()
        out.append((curve, where))
    return out


def with_optimised_turns(result: SearchResult, model, goal: Goal) -> SearchResult:
    """The search's plan, or the grown plan with turns that comes closest to the goal once its
    angles are optimised, when that is predicted closer than the search's plan.

    `model`: the LearnedModel the search ran on (its start image and prediction net). A
    negative goal is left alone: the descent only lowers eq. (5)."""
    with_turn = [i for i, n in enumerate(result.nodes) if any(a.turn for a in n.plan)]
    if goal.negative or not with_turn:
        return result
    t0 = time.perf_counter()
    node = result.nodes[with_turn[goal.best(np.array([result.nodes[i].loss for i in with_turn]))]]
    found = optimise_turns(model.net, model.image, node.plan, goal)
    if found.loss >= result.loss:
        result.seconds += time.perf_counter() - t0  # the descent counts as planning time
        return result
    nodes, at = list(result.nodes), 0
    for a in found.plan:  # the plan's states, added to the tree for its picture and its record
        (image, state) = model.predict([nodes[at]], [a])[0]
        nodes.append(Node(nodes[at].plan + (a,), image, state, parent=at))
        nodes[-1].loss, at = float(goal.loss(image[None])[0]), len(nodes) - 1
    seconds = result.seconds + time.perf_counter() - t0
    return SearchResult(nodes, at, seconds, result.expanded, result.per_depth, result.truncated)


GRID_DEG = 5.0  # the angle grid a non-differentiable world model's turns are searched on


def with_searched_turns(result: SearchResult, model, goal: Goal, step_deg: float = GRID_DEG) -> SearchResult:
    """`with_optimised_turns` for a world model that cannot be differentiated (the object world
    model draws with a renderer): the grown plan with turns that comes closest to the goal has
    each of its turns, one after another, tried at every `step_deg` from -180 to 180, the rest
    held; the angle whose predicted last state scores best by eq. (5) is kept. Its dynamics
    take the angle as an input, so no second net is needed. `model`: any WorldModel."""
    with_turn = [i for i, n in enumerate(result.nodes) if any(a.turn for a in n.plan)]
    if goal.negative or not with_turn:
        return result
    t0 = time.perf_counter()
    node = result.nodes[with_turn[goal.best(np.array([result.nodes[i].loss for i in with_turn]))]]
    root = result.nodes[0]
    grid = [float(a) for a in np.arange(-180.0, 180.0 + 1e-9, step_deg) if abs(a) > 1e-9]
    plan, best_loss = node.plan, float(node.loss)
    for i in [k for k, a in enumerate(node.plan) if a.turn]:
        plans = [plan[:i] + (plan[i].with_turn(angle),) + plan[i + 1 :] for angle in grid]
        ends = [Node(p, *steps[-1]) for p, steps in zip(plans, _rolled_out(model, root, plans), strict=True)]
        # the model's own score, as the tree's nodes have it (expected eq. 5 where it branches)
        losses = model.score(goal, ends).loss
        k = goal.best(losses)
        if losses[k] < best_loss:
            plan, best_loss = plans[k], float(losses[k])
    if best_loss >= result.loss:
        result.seconds += time.perf_counter() - t0  # the search counts as planning time
        return result
    nodes, at = list(result.nodes), 0
    for a, (image, state) in zip(plan, _rolled_out(model, root, [plan])[0], strict=True):
        nodes.append(Node(nodes[at].plan + (a,), image, state, parent=at))
        nodes[-1].loss, at = float(model.score(goal, nodes[-1:]).loss[0]), len(nodes) - 1
    seconds = result.seconds + time.perf_counter() - t0
    return SearchResult(nodes, at, seconds, result.expanded, result.per_depth, result.truncated)


def _rolled_out(
    model, root: Node, plans: list[tuple[Affordance, ...]]
) -> list[list[tuple[np.ndarray, object]]]:
    """Per plan (all of one length), (image, state) after each of its steps, predicted by
    `model` from `root`; each step of every plan in one call."""
    nodes = [root] * len(plans)
    out: list[list[tuple[np.ndarray, object]]] = [[] for _ in plans]
    for t in range(len(plans[0])):
        children = model.predict(nodes, [p[t] for p in plans])
        nodes = [
            Node(n.plan + (p[t],), image, state)
            for n, p, (image, state) in zip(nodes, plans, children, strict=True)
        ]
        for steps, child in zip(out, children, strict=True):
            steps.append(child)
    return out
