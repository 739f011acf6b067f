"""P^a over objects: one interaction network per affordance type (paper II.C's P^a), with K
outcomes where one start can go two ways.

Each object is a node. Its input is its own state (`state.slot_features`), where it lies from
the affordance's point, and the affordance itself. Rounds of pairwise messages (an interaction
network: a message from every other object, summed, then a residual update of each node) let
an object's fate depend on what touches it. Each node then says, per outcome: does it move
(the gate), does it leave the table, is it held, and if it moves, its change in position and
its new axes. A scene-level head gives the outcomes' probabilities.

eq. (2) on objects: c' = c + dc, where an object the gate calls still is copied exactly (the
counterpart of eq. (3)'s mask: only what moves is predicted).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

import numpy as np
import torch
from torch import nn
from torch.nn import functional as F

from afford.objects.state import (
    CENTRE,
    FEATURES,
    KINDS,
    N_SLOTS,
    POS_SCALE,
    SLOT_KIND,
    axes_quat,
    quat_axes,
    slot_features,
)
from afford.sim.affordance import Col
from afford.sim.affordances import TYPES

ACTION_FEATURES = 3 + 4 + 3 + 1  # position, angle (once and twice round), turn, symmetric
RELATIVE = 4  # the object from the affordance's point: dx, dy, dz, planar distance
PAIR = 4  # between two objects: dx, dy, dz, distance
HEAD = 3 + 3 + 3 + 3  # moves, gone, held logits; change in position (cm); up; along
CM = 100.0  # positions change in centimetres at the nets' outputs


@dataclass
class DynamicsConfig:
    hidden: int = 96
    rounds: int = 2  # message-passing rounds
    outcomes: int = 2  # K: where one start can go two ways
    # training
    steps: int = 16000  # side-effect landings kept improving to here (docs/experiments)
    batch: int = 256
    lr: float = 1e-3
    warmup: int = 200
    grad_clip: float = 1.0
    eval_every: int = 500
    log_every: int = 50
    seed: int = 0
    threads: int = 2
    spread: float = 0.05  # share of the loss every outcome takes, so none is left untrained
    moved: float = 0.002  # metres: an object that moved less than this counts as still
    turned_deg: float = 3.0  # ... and whose axes turned less than this
    # The outcome head's logits are divided by this (objects/calibration.py: fitted on val
    # after training; 1: as trained).
    outcome_temperature: float = 1.0

    # Fields that shipped files store but this code does not vary: each with the one value it
    # runs (training/fields.from_dict refuses a stored config that asks for another).
    removed: ClassVar[dict[str, object]] = {
        "arm_path": False,
        "frames": False,
        "input_noise": 0.0,
        "mirror": False,
        "rare_weight": 1.0,
        "perceived_share": 0.25,
    }


PRESETS = {
    "cpu": DynamicsConfig(),
    "tiny": DynamicsConfig(hidden=16, rounds=1, steps=40, batch=16, eval_every=20, log_every=5),
}


def _mlp(n_in: int, hidden: int, n_out: int) -> nn.Sequential:
    return nn.Sequential(
        nn.Linear(n_in, hidden), nn.SiLU(), nn.Linear(hidden, hidden), nn.SiLU(), nn.Linear(hidden, n_out)
    )


class Relations(nn.Module):
    """One round of messages: every object hears every other present object.

    The message MLP's first layer is linear in [h_i, h_j, pair], so it is applied to each node
    once and summed over pairs: S nodes cost S products, not S x S."""

    def __init__(self, hidden: int, pair: int = PAIR):
        super().__init__()
        self.sender = nn.Linear(hidden, hidden)
        self.receiver = nn.Linear(hidden, hidden, bias=False)
        self.relation = nn.Linear(pair, hidden, bias=False)
        self.message = nn.Sequential(nn.SiLU(), nn.Linear(hidden, hidden))
        self.node = _mlp(2 * hidden, hidden, hidden)

    def forward(self, h: torch.Tensor, pair: torch.Tensor, mask: torch.Tensor) -> torch.Tensor:
        s = h.shape[1]
        first = self.receiver(h)[:, :, None] + self.sender(h)[:, None] + self.relation(pair)
        others = mask[:, None, :] & ~torch.eye(s, dtype=torch.bool, device=h.device)
        m = self.message(first) * others[..., None]
        return h + self.node(torch.cat([h, m.sum(2)], -1))


class TypeDynamics(nn.Module):
    """P^a for one affordance type."""

    def __init__(self, config: DynamicsConfig):
        super().__init__()
        n_in = FEATURES + RELATIVE + ACTION_FEATURES
        self.k = config.outcomes
        self.encode = _mlp(n_in, config.hidden, config.hidden)
        self.rounds = nn.ModuleList(Relations(config.hidden, PAIR) for _ in range(config.rounds))
        self.head = _mlp(config.hidden, config.hidden, config.outcomes * HEAD)
        self.choose = _mlp(config.hidden, config.hidden, config.outcomes)

    def forward(self, nodes: torch.Tensor, pair: torch.Tensor, mask: torch.Tensor) -> dict[str, torch.Tensor]:
        h = self.encode(nodes)
        for r in self.rounds:
            h = r(h, pair, mask)
        out = self.head(h).view(*h.shape[:2], self.k, HEAD)
        pooled = (h * mask[..., None]).sum(1) / mask.sum(1, keepdim=True).clamp(min=1)
        return {
            "moves": out[..., 0],
            "gone": out[..., 1],
            "held": out[..., 2],
            "dpos": out[..., 3:6],
            "up": F.normalize(out[..., 6:9], dim=-1, eps=1e-6),
            "along": F.normalize(out[..., 9:12], dim=-1, eps=1e-6),
            "outcome": self.choose(pooled),
        }


class ObjectDynamics(nn.Module):
    """The P^a of every affordance type; each execution goes through its own type's net."""

    def __init__(self, config: DynamicsConfig):
        super().__init__()
        self.config = config
        self.p = nn.ModuleDict({t: TypeDynamics(config) for t in TYPES})

    def outcomes(self, before: np.ndarray, held: np.ndarray, actions: np.ndarray) -> ObjectOutcomes:
        """`predict` with this net: what every world model's dynamics answer."""
        return predict(self, before, held, actions)

    def forward(self, batch: dict[str, torch.Tensor]) -> dict[str, torch.Tensor]:
        out: dict[str, torch.Tensor] = {}
        nodes = batch["nodes"]
        types = batch["type"]
        for index, name in enumerate(TYPES):
            rows = torch.nonzero(types == index).flatten()
            if len(rows) == 0:
                continue
            part = self.p[name](nodes[rows], batch["pair"][rows], batch["present"][rows])
            for key, value in part.items():
                if key not in out:
                    out[key] = value.new_zeros((len(types), *value.shape[1:]))
                out[key][rows] = value
        return out


# ---------------------------------------------------------------------------- inputs
def action_features(actions: np.ndarray) -> np.ndarray:
    """(N, 7) affordance rows -> (N, ACTION_FEATURES)."""
    angle = np.radians(actions[:, Col.ANGLE])
    turn = np.radians(actions[:, Col.TURN])
    return np.column_stack(
        [
            (actions[:, Col.POSITION] - CENTRE) * POS_SCALE,
            np.cos(angle),
            np.sin(angle),
            np.cos(2 * angle),
            np.sin(2 * angle),
            np.cos(turn),
            np.sin(turn),
            turn / np.pi,
            actions[:, Col.SYMMETRIC],
        ]
    ).astype(np.float32)


def encode_inputs(before: np.ndarray, held: np.ndarray, actions: np.ndarray) -> dict[str, torch.Tensor]:
    """The nets' inputs for N executions: poses (N, slots, 7), held slots (N,), affordance rows
    (N, 7)."""
    nodes, present = slot_features(before, held)
    pos = np.where(present[..., None], np.nan_to_num(before[..., :3]), 0.0)
    rel = (pos - actions[:, None, Col.POSITION]) * POS_SCALE
    rel = np.concatenate([rel, np.linalg.norm(rel[..., :2], axis=-1, keepdims=True)], -1)
    act = np.broadcast_to(action_features(actions)[:, None], (len(actions), N_SLOTS, ACTION_FEATURES))
    parts = [nodes, rel * present[..., None], act]
    delta = (pos[:, None, :, :] - pos[:, :, None, :]) * POS_SCALE  # j seen from i
    pair = np.concatenate([delta, np.linalg.norm(delta, axis=-1, keepdims=True)], -1)
    return {
        "nodes": torch.from_numpy(np.concatenate(parts, -1).astype(np.float32)),
        "pair": torch.from_numpy(pair.astype(np.float32)),
        "present": torch.from_numpy(present),
        "type": torch.from_numpy(actions[:, Col.TYPE].astype(np.int64)),
    }


def encode_targets(
    before: np.ndarray, after: np.ndarray, held_after: np.ndarray, config: DynamicsConfig
) -> dict[str, torch.Tensor]:
    """What happened, per object: moved, gone, held; the change in position (cm), the new axes."""
    was = ~np.isnan(before[..., 0])
    now = ~np.isnan(after[..., 0])
    b = np.nan_to_num(before)
    a = np.where(now[..., None], np.nan_to_num(after), b)
    up_b, along_b = quat_axes(np.where(was[..., None], b[..., 3:7], [1.0, 0, 0, 0]))
    up_a, along_a = quat_axes(np.where(was[..., None], a[..., 3:7], [1.0, 0, 0, 0]))
    shift = np.linalg.norm(a[..., :3] - b[..., :3], axis=-1)
    cos = np.cos(np.radians(config.turned_deg))
    turned = ((up_a * up_b).sum(-1) < cos) | ((along_a * along_b).sum(-1) < cos)
    gone = was & ~now
    moves = was & (gone | (shift > config.moved) | turned)
    held = np.arange(N_SLOTS) == np.asarray(held_after)[:, None]
    moves |= was & held  # the held object always goes with the arm
    t = lambda x: torch.from_numpy(np.ascontiguousarray(x, dtype=np.float32))  # noqa: E731
    return {
        "moves": t(moves),
        "gone": t(gone),
        "held": t(held),
        "dpos": t((a[..., :3] - b[..., :3]) * CM),
        "up": t(up_a),
        "along": t(along_a),
        "lands": t(moves & now),
        "was": t(was),
    }


# ---------------------------------------------------------------------------- loss
def outcome_losses(out: dict[str, torch.Tensor], target: dict[str, torch.Tensor]) -> torch.Tensor:
    """(B, K) each outcome's loss on each execution: the gate, gone and held as classifications
    over the objects on the table, and where each object that moves lands."""
    was = target["was"][..., None]

    def bce(logit: torch.Tensor, y: torch.Tensor) -> torch.Tensor:
        return F.binary_cross_entropy_with_logits(logit, y[..., None].expand_as(logit), reduction="none")

    cls = (
        bce(out["moves"], target["moves"])
        + bce(out["gone"], target["gone"])
        + bce(out["held"], target["held"])
    ) * was
    lands = target["lands"][..., None]
    pos = F.smooth_l1_loss(
        out["dpos"], target["dpos"][:, :, None].expand_as(out["dpos"]), reduction="none"
    ).sum(-1)
    up = 1 - (out["up"] * target["up"][:, :, None]).sum(-1)
    # The block's length has no sign (it is the same block turned 180 degrees); others' x axes
    # are not seen at all (a ball, a round cup) or matter only as a toppled support's roll.
    along = 1 - (out["along"] * target["along"][:, :, None]).sum(-1) ** 2
    is_block = torch.from_numpy(SLOT_KIND == KINDS.index("block")).to(along)[None, :, None]
    reg = (pos + 4 * up + 4 * along * is_block) * lands
    return (cls + reg).sum(1)


def mixture_loss(
    out: dict[str, torch.Tensor], target: dict[str, torch.Tensor], spread: float
) -> tuple[torch.Tensor, dict]:
    """Winner takes all over the K outcomes (each execution trains the outcome nearest to what
    happened, plus a small share to every outcome), and the outcome head learns which wins."""
    per = outcome_losses(out, target)
    best = per.detach().argmin(1)
    wta = per.gather(1, best[:, None]).squeeze(1)
    choice = F.cross_entropy(out["outcome"], best)
    loss = ((1 - spread) * wta + spread * per.mean(1)).mean() + choice
    parts = {"wta": float(wta.detach().mean()), "choice": float(choice.detach())}
    return loss, parts


# ---------------------------------------------------------------------------- predicting
@dataclass
class ObjectOutcomes:
    """K predicted next states of N executions: poses (N, K, slots, 7) (NaN: off the table),
    held slots (N, K) (-1: none), probabilities (N, K)."""

    poses: np.ndarray
    held: np.ndarray
    probability: np.ndarray

    def likeliest(self) -> tuple[np.ndarray, np.ndarray]:
        k = self.probability.argmax(1)
        rows = np.arange(len(k))
        return self.poses[rows, k], self.held[rows, k]


@torch.no_grad()
def predict(net: ObjectDynamics, before: np.ndarray, held: np.ndarray, actions: np.ndarray) -> ObjectOutcomes:
    """Every outcome of N executions from their start states (eq. 2 on objects)."""
    net.eval()
    out = net(encode_inputs(before, held, actions))
    moves = torch.sigmoid(out["moves"]).numpy() > 0.5  # (N, S, K)
    gone = torch.sigmoid(out["gone"]).numpy() > 0.5
    held_p = torch.sigmoid(out["held"]).numpy()
    n, s, k = moves.shape
    poses = np.repeat(before[:, None], k, axis=1).astype(np.float64)  # (N, K, S, 7)
    dpos = out["dpos"].numpy().transpose(0, 2, 1, 3) / CM
    quat = axes_quat(out["up"].numpy().astype(float), out["along"].numpy().astype(float)).transpose(
        0, 2, 1, 3
    )
    was = ~np.isnan(before[..., 0])[:, None, :]
    move = moves.transpose(0, 2, 1) & was
    poses[..., :3] = np.where(move[..., None], poses[..., :3] + dpos, poses[..., :3])
    poses[..., 3:7] = np.where(move[..., None], quat, poses[..., 3:7])
    poses[gone.transpose(0, 2, 1) & was] = np.nan
    hp = np.where(was, held_p.transpose(0, 2, 1), 0.0)
    held_next = np.where(hp.max(-1) > 0.5, hp.argmax(-1), -1)
    probability = torch.softmax(out["outcome"] / net.config.outcome_temperature, -1).numpy()
    return ObjectOutcomes(poses.astype(np.float32), held_next.astype(np.int64), probability)
