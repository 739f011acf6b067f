"""Two prediction nets as one world model: each outcome drawn by the net trained for it.

A two-outcome net (`hypotheses_by=effect`: a canonical outcome, a side-effect outcome and a
head that says how likely the second is) trained with the side-effect term (`loss_effect`)
draws side effects far better than one trained without it, and canonical effects worse: the
term's gradients reach the layers both outcomes share, so the planner loses canonical tasks
(docs/experiments/landings.md). A pair keeps them apart without a compromise in either:
`main`, the net trained for the canonical outcome, draws it and its head says how likely the
side effect is; `side`, the net trained with the term, draws the side effect. Neither net's
weights touch the other's.

Each net keeps its own latent and memory trace (eq. 2), so a state of the pair is both nets'
latents side by side on the channel axis (main's first): every planner that stacks, splits or
branches latents handles a pair as it handles one net. Both nets step every outcome from the
same image, the one the pair drew, so a side effect the side net drew stays in the image the
main net's next difference (eq. 3) is applied to. Outcome k's state carries each net's own
k-th latent: after a side effect each net goes on from its own idea of it.

The cost: every step runs E, P^a and D of both nets, about twice one net's.
"""

from __future__ import annotations

from pathlib import Path

import torch
from torch import nn

from afford.prediction.model import Hypotheses, Outcomes, PredictionNet, Step
from afford.prediction.rollout import Rollouts

# The side-effect outcome's net beside a weights folder's prediction net: a folder holding it
# loads as a pair (prediction/evaluate.py: load_net).
SIDE_FILE = "side-effects.safetensors"
CANONICAL, SIDE = 0, 1  # the outcomes of a net trained by effect labels


def side_file(path: str | Path) -> Path:
    """Where the side-effect net of the prediction checkpoint at `path` would be."""
    return Path(path).with_name(SIDE_FILE)


class PairedNet(Rollouts, nn.Module):
    """`main`'s canonical outcome and choice head, `side`'s side-effect outcome (module doc)."""

    def __init__(self, main: PredictionNet, side: PredictionNet):
        super().__init__()
        for name, net in (("main", main), ("side", side)):
            c = net.config
            if c.outcomes.hypotheses != 2 or c.outcomes.hypotheses_by != "effect":
                raise ValueError(f"a pair's {name} net needs hypotheses=2 and hypotheses_by=effect")
            if c.model.variance:
                raise ValueError(f"a pair's {name} net has a variance head: a pair draws no variance")
        if main.config.model.architecture != side.config.model.architecture:
            raise ValueError("a pair's nets need one architecture (their latents lie side by side)")
        self.main, self.side = main, side
        self.config = main.config  # the head's calibration and cut-off, threads: the main net's
        with torch.no_grad():
            size = main.config.model.image_size
            latent, memory = main.encode(torch.zeros(1, main.config.model.channels, size, size))
        self.split = (latent.shape[1], memory.shape[1])  # main's latent and memory channels

    def encode(self, image: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
        """E of both nets: their latents and memory traces, main's first on the channel axis."""
        (lm, mm), (ls, ms) = self.main.encode(image), self.side.encode(image)
        return torch.cat([lm, ls], 1), torch.cat([mm, ms], 1)

    def probabilities(self, logits: torch.Tensor, rows: torch.Tensor | None = None) -> torch.Tensor:
        """The main net's head, read through its calibration."""
        return self.main.probabilities(logits, rows)

    def _outcomes(self, latent, memory, image, rows):
        """Every outcome: next latents and memories (B, K, ...) of both nets side by side, the
        pair's candidates (B, K, C, H, W) and differences, and the main head's logits."""
        axis = 2  # (B, K, channels, ...)
        states, drawn = [], []
        for net, lat, mem in zip(
            (self.main, self.side),
            latent.split(self.split[0], 1),
            memory.split(self.split[1], 1),
            strict=True,
        ):
            c = net.candidates(lat, mem, image, rows)
            states.append(net.outcome_states(lat, c.dc, c.memory))
            drawn.append((c.images, c.differences, c.logits))
        (cm, dm, logits), (cs, ds, _) = drawn
        candidates = torch.stack([cm[:, CANONICAL], cs[:, SIDE]], 1)
        differences = torch.stack([dm[:, CANONICAL], ds[:, SIDE]], 1)
        next_latent = torch.cat([states[0][0], states[1][0]], axis)
        next_memory = torch.cat([states[0][1], states[1][1]], axis)
        return next_latent, next_memory, candidates, differences, logits

    def step_outcomes(self, latent, memory, image, rows) -> Outcomes:
        """Both outcomes of a step, each its own state (planning/branches.py)."""
        next_latent, next_memory, candidates, _, logits = self._outcomes(latent, memory, image, rows)
        return Outcomes(next_latent, next_memory, candidates, self.probabilities(logits, rows))

    def step_hypotheses(self, latent, memory, image, rows, truth=None, label=None) -> Step:
        """PredictionNet.step_hypotheses for the pair: the outcome carried on picked by the main
        net's rule (`PredictionNet.pick`) among the pair's candidates. No variance."""
        latents, memories, candidates, differences, logits = self._outcomes(latent, memory, image, rows)
        picked = self.main.pick(candidates, differences, logits, image, rows, truth, label)
        at = torch.arange(len(image), device=image.device)
        return Step(
            latents[at, picked],
            memories[at, picked],
            candidates[at, picked],
            differences[at, picked],
            Hypotheses(candidates, logits, picked),
        )
