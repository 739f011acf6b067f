"""The EM*D prediction pathway with differential prediction (paper II.C).

E encodes a state image to a latent c. For each action, the P module of its affordance type
turns (c, memory trace, action) into a latent difference dc and the next memory trace;
c' = c + dc (eq. 2). D decodes dc to an (n+1)-channel difference image whose last channel is a
mask, applied to the current image by eq. (3). The action vector's last values are the RGBD
of the affordance's pixel, read from the current image: the real one at the first step, the
predicted one after.

Two architectures fill in E, P^a and D (`config.model.architecture`): "dense", the paper's vector
latent (`dense.py`, the `paper` preset), and "spatial", a latent grid that learns on a CPU
(`spatial.py`, the `cpu` preset). This module holds what they share: routing by type, the
action vector, eq. (2) and (3); the rollout over a sequence of actions is rollout.py's.
"""

from __future__ import annotations

from dataclasses import dataclass

import torch
from torch import nn

from afford.prediction.config import CHANGED, OutcomesConfig, PredictionConfig
from afford.prediction.dense import DenseDecoder, DenseEncoder, DenseP
from afford.prediction.layers import apply_difference, clamped_tanh, normalise_latent
from afford.prediction.rollout import Rollouts
from afford.prediction.spatial import SpatialDecoder, SpatialEncoder, SpatialP
from afford.sim.affordance import Col
from afford.sim.camera import world_to_pixel

__all__ = ["PredictionNet", "affordance_pixel", "apply_difference", "clamped_tanh", "normalise_latent"]

# architecture -> (E, P^a, D)
ARCHITECTURES: dict[str, tuple[type[nn.Module], type[nn.Module], type[nn.Module]]] = {
    "dense": (DenseEncoder, DenseP, DenseDecoder),
    "spatial": (SpatialEncoder, SpatialP, SpatialDecoder),
}


def affordance_pixel(images: torch.Tensor, positions: torch.Tensor) -> torch.Tensor:
    """RGBD (B, C) of the pixel each world position (B, 3) projects to (the camera model)."""
    px = world_to_pixel(positions).floor().long()
    col = px[:, 0].clamp(0, images.shape[-1] - 1)
    row = px[:, 1].clamp(0, images.shape[-2] - 1)
    return images[torch.arange(len(images), device=images.device), :, row, col]


@dataclass
class Hypotheses:
    """A step's K candidate outcomes (config.outcomes.hypotheses > 1): the images (B, K, C, H, W), the
    choice head's logits (B, K), and the one picked (B,): the winner, nearest the truth, in
    training; the most likely one otherwise."""

    candidates: torch.Tensor
    logits: torch.Tensor
    picked: torch.Tensor


@dataclass
class Step:
    """One step carried on (`PredictionNet.step_hypotheses`): the next latent and memory trace
    (eq. 2), the image drawn and D's difference image (B, C+1, H, W: eq. (3)'s new values and,
    last, its mask), and the K candidates (None with one hypothesis)."""

    latent: torch.Tensor
    memory: torch.Tensor
    image: torch.Tensor
    difference: torch.Tensor
    hypotheses: Hypotheses | None = None


@dataclass
class Candidates:
    """A step's K candidates before one is carried on (`PredictionNet.candidates`): dc and the
    memory trace ((B, K, ...) when forked in the latent, else (B, ...)), the images
    (B, K, C, H, W), D's differences (B, K, C+1, H, W) and the choice head's logits (B, K)."""

    dc: torch.Tensor
    memory: torch.Tensor
    images: torch.Tensor
    differences: torch.Tensor
    logits: torch.Tensor


@dataclass
class Outcomes:
    """Every outcome of a step (`PredictionNet.step_outcomes`), on a second axis of K: the next
    latents, memory traces and images (B, K, ...) and the probability of each (B, K)."""

    latent: torch.Tensor
    memory: torch.Tensor
    images: torch.Tensor
    probability: torch.Tensor


# Weight of what a candidate would draw (its new values, before eq. (3)'s mask) in choosing the
# winner: where every candidate's mask is still shut their outputs tie, and the values break
# the tie by what each would draw once open.
VALUES_TIE_BREAK = 0.1


@torch.no_grad()
def winners(candidates: torch.Tensor, differences: torch.Tensor, image: torch.Tensor, truth: torch.Tensor):
    """(B,) the candidate nearest the truth where the truth changed (by more than CHANGED from
    the step's input): the hypotheses are alternatives of what changes, and over the unchanged
    rest of the image, where every candidate copies the input alike, an outcome drawn right
    would be outvoted by noise. Over the whole image where nothing changed. `differences`
    (B, K, C+1, H, W): each candidate's values and mask."""
    changed = ((truth - image).abs().amax(1) > CHANGED).float()[:, None]  # (B, 1, H, W)
    changed = torch.where(changed.sum((2, 3), keepdim=True) > 0, changed, torch.ones_like(changed))
    errors = (candidates - truth[:, None]).abs().mean(2)  # (B, K, H, W)
    errors = errors + VALUES_TIE_BREAK * (differences[:, :, :-1] - truth[:, None]).abs().mean(2)
    return ((errors * changed).sum((2, 3)) / changed.sum((2, 3))).argmin(1)


# Where K candidate outcomes part (config.outcomes.fork): in D's last layer, or in P^a's last block.
FORKS = ("decoder", "latent")


class PredictionNet(Rollouts, nn.Module):
    def __init__(self, config: PredictionConfig):
        super().__init__()
        m, o = config.model, config.outcomes
        if m.architecture not in ARCHITECTURES:
            raise ValueError(
                f"unknown prediction architecture {m.architecture!r}; expected one of {sorted(ARCHITECTURES)}"
            )
        if o.hypotheses < 1 or (o.hypotheses > 1 and m.architecture != "spatial"):
            raise ValueError("hypotheses: 1, or more with the spatial architecture")
        if o.hypotheses_by not in ("winner", "effect"):
            raise ValueError(f"hypotheses_by: 'winner' or 'effect', not {o.hypotheses_by!r}")
        if o.fork not in FORKS:
            raise ValueError(f"fork: one of {', '.join(FORKS)}, not {o.fork!r}")
        if o.hypotheses_by == "effect" and o.hypotheses != 2:
            raise ValueError("hypotheses_by=effect needs hypotheses=2: a canonical and a side-effect outcome")
        encoder, p_module, decoder = ARCHITECTURES[m.architecture]
        self.config = config
        self.encoder = encoder(config)
        self.decoder = decoder(config)
        self.modules_by_type = nn.ModuleList(p_module(config) for _ in m.types)
        # Channels-last: the small convolutions over 128x128 images run ~3x faster on CPUs.
        self.to(memory_format=torch.channels_last) if m.architecture == "dense" else None
        self.register_buffer("pos_centre", torch.tensor(m.position_centre), persistent=False)
        self.register_buffer("pos_scale", torch.tensor(m.position_scale), persistent=False)

    @property
    def outcomes(self) -> OutcomesConfig:
        """The config's outcomes record: how many D draws, where they part, the head's scaling."""
        return self.config.outcomes

    def encode(self, image: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
        """E: (c_0, m_0) for images (B, C, H, W); the memory trace starts at zeros."""
        latent = self.encoder(image)
        return latent, self.encoder.initial_memory(latent)

    def action_vector(self, rows: torch.Tensor, image: torch.Tensor) -> torch.Tensor:
        """Affordance rows (B, 7: type, x, y, z, angle, symmetric, turn) -> the P input (B, 9)."""
        pos = rows[:, Col.POSITION]
        pixel = (
            affordance_pixel(image, pos) if self.config.model.pixel_input else image.new_zeros(len(rows), 4)
        )
        return torch.cat(
            [
                (pos - self.pos_centre) / self.pos_scale,
                (rows[:, Col.ANGLE, None] % 360.0) / 360.0,
                rows[:, Col.TURN, None] / 90.0,
                pixel,
            ],
            -1,
        )

    def _p_step(self, latent, memory, image, rows):
        """Each example through the P^a of its own type: (dc, next memory trace)."""
        vector = self.action_vector(rows, image)
        pixel = world_to_pixel(rows[:, Col.POSITION])
        types = rows[:, Col.TYPE].long()
        dc = memory_out = None
        for t, module in enumerate(self.modules_by_type):
            idx = torch.nonzero(types == t).flatten()
            if not len(idx):
                continue
            d, m = module(latent[idx], memory[idx], vector[idx], pixel[idx])
            if dc is None:
                dc = latent.new_zeros((len(rows), *d.shape[1:]))
                memory_out = memory.new_zeros((len(rows), *m.shape[1:]))
            dc = dc.index_copy(0, idx, d)
            memory_out = memory_out.index_copy(0, idx, m)
        return dc, memory_out

    def candidates(self, latent, memory, image, rows) -> Candidates:
        """K > 1: every candidate of one step (`Candidates`)."""
        dc, memory_out = self._p_step(latent, memory, image, rows)
        b, k = len(image), self.outcomes.hypotheses
        repeated = image.repeat_interleave(k, 0)
        forked = self.outcomes.fork == "latent"  # dc (B, K, C, h, w): each candidate its own dc
        difference = self.decoder(dc.flatten(0, 1), repeated) if forked else self.decoder(dc, image)
        differences = difference.view(b, k, -1, *difference.shape[-2:])
        candidates = apply_difference(repeated, differences.flatten(0, 1))  # eq. (3)
        return Candidates(
            dc,
            memory_out,
            candidates.view(b, k, *image.shape[1:]),
            differences,
            self.decoder.choice_logits(dc),
        )

    def step_outcomes(self, latent, memory, image, rows) -> Outcomes:
        """Every outcome of one step, each carried on as its own state, with the choice head's
        probability of each: what a planner that keeps the alternatives (planning/branches.py)
        grows. One outcome of probability 1 for a one-hypothesis net."""
        if self.outcomes.hypotheses == 1:
            step = self.step_hypotheses(latent, memory, image, rows)
            return Outcomes(
                step.latent[:, None],
                step.memory[:, None],
                step.image[:, None],
                image.new_ones(len(image), 1),
            )
        c = self.candidates(latent, memory, image, rows)
        next_latent, memory_out = self.outcome_states(latent, c.dc, c.memory)
        return Outcomes(next_latent, memory_out, c.images, self.probabilities(c.logits, rows))

    def outcome_states(self, latent, dc, memory_out) -> tuple[torch.Tensor, torch.Tensor]:
        """K > 1: every candidate's next latent and memory trace (B, K, ...) from `candidates`'
        dc and memory (one for all candidates unless forked in the latent)."""
        k = self.outcomes.hypotheses
        if self.outcomes.fork != "latent":  # one dc and memory for every candidate
            dc = dc[:, None].expand(-1, k, *dc.shape[1:])
            memory_out = memory_out[:, None].expand(-1, k, *memory_out.shape[1:])
        next_latent = self.encoder.renormalise((latent[:, None] + dc).flatten(0, 1))  # eq. (2)
        return next_latent.view(*dc.shape[:2], *next_latent.shape[1:]), memory_out

    def probabilities(self, logits: torch.Tensor, rows: torch.Tensor | None = None) -> torch.Tensor:
        """(B, K) how likely each outcome is, from the choice head's logits: by effect, the
        side effect's logit read through the config's calibration (per action type where the
        config has one and the action rows (B, 7) are given); else their softmax."""
        logits = logits.float()
        if self.outcomes.hypotheses_by != "effect":
            return logits.softmax(1)
        o = self.outcomes
        scale, bias = o.choice_scale, o.choice_bias
        if o.choice_scales and rows is not None:
            kind = rows[:, Col.TYPE].long().to(logits.device)
            scale, bias = logits.new_tensor(o.choice_scales)[kind], logits.new_tensor(o.choice_biases)[kind]
        side = torch.sigmoid(scale * (logits[:, 1] - logits[:, 0]) + bias)
        return torch.stack([1 - side, side], 1)

    def step_hypotheses(
        self,
        latent,
        memory,
        image,
        rows,
        truth: torch.Tensor | None = None,
        label: torch.Tensor | None = None,
    ) -> Step:
        """One step carried on (`Step`): with K > 1 hypotheses the candidate carried on is the
        one `label` (B,) names where it is given (training by effect labels), else the one
        nearest `truth` where that is given (training's winner-takes-all), else the one the
        choice head finds most likely."""
        k = self.outcomes.hypotheses
        if k == 1:
            dc, memory_out = self._p_step(latent, memory, image, rows)
            difference = self.decoder(dc, image)
            next_latent = self.encoder.renormalise(latent + dc)  # eq. (2)
            drawn = apply_difference(image, difference)  # eq. (3)
            return Step(next_latent, memory_out, drawn, difference)
        c = self.candidates(latent, memory, image, rows)
        picked = self.pick(c.images, c.differences, c.logits, image, rows, truth, label)
        at = torch.arange(len(image), device=image.device)
        dc, memory_out = c.dc, c.memory
        if self.outcomes.fork == "latent":  # the candidate carried on gives eq. (2) its dc, and its memory
            dc, memory_out = dc[at, picked], memory_out[at, picked]
        next_latent = self.encoder.renormalise(latent + dc)  # eq. (2)
        return Step(
            next_latent,
            memory_out,
            c.images[at, picked],  # eq. (3), drawn by the candidate
            c.differences[at, picked],
            Hypotheses(c.images, c.logits, picked),
        )

    def pick(self, candidates, differences, logits, image, rows, truth=None, label=None) -> torch.Tensor:
        """(B,) the candidate carried on: the one `label` names, else the one nearest `truth`,
        else by the choice head (`step_hypotheses`)."""
        if label is not None:
            return label.long()
        if truth is not None:
            return winners(candidates, differences, image, truth)
        if self.outcomes.hypotheses_by == "effect":
            return (self.probabilities(logits, rows)[:, 1] > self.outcomes.effect_threshold).long()
        return logits.argmax(1)

    def adapt_state(self, state: dict[str, torch.Tensor]) -> dict[str, torch.Tensor]:
        """Weights of a one-hypothesis net for this one (fine-tuning the shipped net with K
        hypotheses): D's output repeated for each candidate, each a little apart so that
        winner-takes-all can tell them apart, and the choice head as initialised (uniform)."""
        k = self.outcomes.hypotheses
        own = self.state_dict()
        state = dict(state)
        if k == 1 or "decoder.choice.weight" in state:  # already this many outcomes
            return state

        def near(w: torch.Tensor) -> torch.Tensor:  # a copy a little apart (a lone value: exact)
            return w + 0.01 * w.std() * torch.randn_like(w) if w.numel() > 1 else w.clone()

        for name in ("decoder.out.weight", "decoder.out.bias"):
            if name in state and state[name].shape[0] * k == own[name].shape[0]:
                state[name] = torch.cat([state[name]] + [near(state[name]) for _ in range(k - 1)], 0)
        # Forked in the latent: each fork starts as a copy of its P^a's last blocks and output layer.
        for name in own:
            if ".forks." in name and self._fork_source(name) in state:
                state[name] = near(state[self._fork_source(name)])
        for name in own:
            if name.startswith("decoder.choice"):
                state[name] = own[name]
        return state

    def _fork_source(self, name: str) -> str:
        """The trunk's parameter a fork's parameter copies: its `block` the P^a's last block,
        its `out` the P^a's output layer."""
        head, _, tail = name.partition(".forks.")
        part = tail.split(".", 1)[1]  # "block.conv1.weight" or "out.bias"
        if part.startswith("block."):
            return f"{head}.blocks.{self.config.model.p_blocks - 1}.{part[len('block.') :]}"
        return f"{head}.{part}"
