"""Rollouts: a prediction net stepped through a sequence of actions (paper II.C, Fig. 3).

What every prediction net shares once it has `encode` and `step_hypotheses`: one step's
image and latent, and the rollout of a batch of runs of different lengths, each step from the
previous prediction.
"""

from __future__ import annotations

from dataclasses import dataclass

import torch


@dataclass
class Rollout:
    """A batch rolled out (`Rollouts.rollout_hypotheses`): the predicted states (B, L, C, H, W)
    and D's differences (B, L, C+1, H, W) after each of L actions; with K > 1 hypotheses every
    step's candidates (B, L, K, C, H, W), choice logits (B, L, K) and picks (B, L) (else None)."""

    states: torch.Tensor
    differences: torch.Tensor
    candidates: torch.Tensor | None = None
    logits: torch.Tensor | None = None
    picks: torch.Tensor | None = None


class Rollouts:
    """Steps and rollouts from a net's `encode(image)` and `step_hypotheses(latent, memory,
    image, rows, truth, label)`, which returns a `Step` (model.py)."""

    def step_with_difference(self, latent, memory, image, rows):
        """One prediction step, also returning D's difference image (B, C+1, H, W): eq. (3)'s
        new values and, last, its mask."""
        step = self.step_hypotheses(latent, memory, image, rows)
        return step.latent, step.memory, step.image, step.difference

    def step(self, latent, memory, image, rows):
        """One prediction: (c_i, m_i, s_i, a_i) -> (c_{i+1}, m_{i+1}, s_{i+1}).

        Each example goes through the P module of its own affordance type.
        """
        return self.step_with_difference(latent, memory, image, rows)[:3]

    def rollout_with_differences(
        self, image: torch.Tensor, actions: torch.Tensor, steps: torch.Tensor | None = None
    ) -> tuple[torch.Tensor, torch.Tensor]:
        """Predicted states (B, L, C, H, W) and D's differences (B, L, C+1, H, W) after each of
        L actions.

        With `steps` (B,), run k stops after steps[k] actions (its later outputs are zeros):
        padded steps of a batch cost nothing.
        """
        rolled = self.rollout_hypotheses(image, actions, steps)
        return rolled.states, rolled.differences

    def rollout_hypotheses(
        self,
        image: torch.Tensor,
        actions: torch.Tensor,
        steps: torch.Tensor | None = None,
        truth: torch.Tensor | None = None,
        labels: torch.Tensor | None = None,
    ) -> Rollout:
        """Every step of each run (`Rollout`); with `truth` (B, L, C, H, W) each step carries
        on its winner, with `labels` (B, L) the candidate they name (`step_hypotheses`)."""
        b, length = actions.shape[:2]
        at = image.device
        order = (
            torch.arange(b, device=at)
            if steps is None
            else torch.argsort(steps, descending=True, stable=True)
        )
        active = (
            torch.full((length,), b, device=at)
            if steps is None
            else (steps[order][None, :] > torch.arange(length, device=at)[:, None]).sum(1)
        )
        image = image[order]
        acts = actions[order]
        truth = None if truth is None else truth[order]
        labels = None if labels is None else labels[order]
        latent, memory = self.encode(image)
        states = differences = candidates = logits = picks = None
        for i in range(length):
            n = int(active[i])
            if n == 0:
                break
            step = self.step_hypotheses(
                latent[:n],
                memory[:n],
                image[:n],
                acts[:n, i],
                None if truth is None else truth[:n, i],
                None if labels is None else labels[:n, i],
            )
            latent, memory, image, difference = step.latent, step.memory, step.image, step.difference
            hyp = step.hypotheses
            if states is None:
                states = image.new_zeros((b, length, *image.shape[1:]))
                differences = difference.new_zeros((b, length, *difference.shape[1:]))
                if hyp is not None:
                    candidates = hyp.candidates.new_zeros((b, length, *hyp.candidates.shape[1:]))
                    logits = hyp.logits.new_zeros((b, length, hyp.logits.shape[1]))
                    picks = hyp.picked.new_zeros((b, length))
            states[order[:n], i] = image
            differences[order[:n], i] = difference
            if hyp is not None:
                candidates[order[:n], i] = hyp.candidates
                logits[order[:n], i] = hyp.logits
                picks[order[:n], i] = hyp.picked
        return Rollout(states, differences, candidates, logits, picks)

    # Training's forward pass: a call through the module (`net(...)`), so that
    # DistributedDataParallel sees it.
    forward = rollout_hypotheses

    def rollout(
        self, image: torch.Tensor, actions: torch.Tensor, steps: torch.Tensor | None = None
    ) -> torch.Tensor:
        """Predicted states (B, L, C, H, W) after each of L actions (B, L, 7) from images (B, C, H, W)."""
        return self.rollout_with_differences(image, actions, steps)[0]
