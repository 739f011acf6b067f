"""Pieces both prediction architectures share: eq. (3), D's output, the latent normalisation."""

from __future__ import annotations

import torch


def normalise_latent(a: torch.Tensor) -> torch.Tensor:
    """The authors' latent normalisation: a / sqrt(1 + sum a^2), keeping the norm below 1."""
    return a / torch.sqrt(1 + (a * a).sum(-1, keepdim=True))


def clamped_tanh(x: torch.Tensor) -> torch.Tensor:
    """tanh clamped to [0, 1] (the authors' D output), with tanh's gradient through the clamp.

    The clamp lets the mask be exactly 0, so eq. (3) copies unchanged pixels exactly; passing
    the gradient straight through it keeps a closed mask able to open again where a change
    appears (a plain clamp would leave it dead).
    """
    t = torch.tanh(x)
    return t + (t.clamp(0.0, 1.0) - t).detach()


def apply_difference(state: torch.Tensor, difference: torch.Tensor) -> torch.Tensor:
    """Eq. (3): s_{i+1} = mask * diff + (1 - mask) * s_i, the mask being the last channel."""
    mask = difference[:, -1:]
    return mask * difference[:, :-1] + (1 - mask) * state
