"""Goal images and the plan loss of paper II.D.

A goal is an image patch no larger than the state image: RGBD, or RGB only (channels the loss
ignores are simply dropped). The loss of a (predicted) state is the smallest mean squared
error between the patch and any same-sized window of the state, eq. (5). A positive goal
picks the plan of least loss, a negative goal ("make this disappear") the greatest, eq. (4).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from afford.errors import UserError

CHANNELS = {"rgbd": 4, "rgb": 3}
STATES_AT_ONCE = 8  # eq. (5)'s states per FFT: measured, 8 of 1-64 the fastest for 313 of 128 x 128 x 4


class GoalError(UserError):
    """A goal that cannot be used; the message names the problem."""


@dataclass(frozen=True)
class Goal:
    """patch: (h, w, C) float image in [0, 1] with C = 4 (RGBD) or 3 (RGB)."""

    patch: np.ndarray
    negative: bool = False

    def __post_init__(self):
        p = self.patch
        if p.ndim != 3 or p.shape[2] not in CHANNELS.values():
            raise GoalError(f"goal patch must be (h, w, 3) or (h, w, 4), not {p.shape}")
        if not np.all(np.isfinite(p)) or p.min() < 0 or p.max() > 1:
            raise GoalError("goal patch values must lie in [0, 1]")

    @property
    def channels(self) -> str:
        return "rgbd" if self.patch.shape[2] == 4 else "rgb"

    def loss(self, states: np.ndarray) -> np.ndarray:
        """Eq. (5) for a batch of states (B, H, W, 4) -> (B,)."""
        return window_mse(self.patch, states[..., : self.patch.shape[2]]).min(axis=(1, 2))

    def loss_torch(self, states):
        """Eq. (5) for a batch of torch states (B, C, H, W) -> (B,), differentiable in the
        states (through the best window): what gradient descent on an action runs on."""
        return window_mse_torch(self.patch, states[:, : self.patch.shape[2]]).amin(dim=(1, 2))

    def best(self, losses: np.ndarray) -> int:
        """Eq. (4): argmin for a positive goal, argmax for a negative one."""
        return int(np.argmax(losses) if self.negative else np.argmin(losses))


def window_mse(patch: np.ndarray, states: np.ndarray) -> np.ndarray:
    """MSE between `patch` (h, w, C) and every window of `states` (B, H, W, C).

    Returns (B, H - h + 1, W - w + 1): entry [b, y, x] compares the patch with the window whose
    top-left pixel is (row y, column x). Expands the square, so the cross term is one
    correlation per channel, done by FFT, and the window sums of squares come from an
    integral image: cost does not grow with the patch size.
    """
    states = np.asarray(states)  # to float64 a chunk at a time, below
    if states.ndim == 3:
        states = states[None]
    g = np.asarray(patch, dtype=np.float64)
    h, w, c = g.shape
    _, H, W, cs = states.shape
    if cs != c:
        raise GoalError(f"goal patch has {c} channels but the states have {cs}")
    if h > H or w > W:
        raise GoalError(f"goal patch {h}x{w} is larger than the state image {H}x{W}")
    fg = np.fft.rfft2(g[::-1, ::-1], s=(H, W), axes=(0, 1))
    # A few states at a time: the arrays of a whole depth of a tree (hundreds of states) fall
    # out of the caches, 4-5 times slower in one call; each state's result is the same.
    parts = [
        _window_mse(states[i : i + STATES_AT_ONCE], g, fg) for i in range(0, len(states), STATES_AT_ONCE)
    ]
    return np.concatenate(parts) if parts else np.zeros((0, H - h + 1, W - w + 1))


def _window_mse(states: np.ndarray, g: np.ndarray, fg: np.ndarray) -> np.ndarray:
    h, w, c = g.shape
    states = states.astype(np.float64)
    _, H, W, _ = states.shape
    # Cross term: sum over the window of s * g, for every window (correlation = convolution
    # with the flipped patch, whose transform is fg).
    fs = np.fft.rfft2(states, axes=(1, 2))
    cross = np.fft.irfft2(fs * fg[None], s=(H, W), axes=(1, 2)).sum(axis=3)
    cross = cross[:, h - 1 :, w - 1 :]
    # Window sums of s^2 from a zero-padded integral image.
    sq = np.pad((states**2).sum(axis=3), ((0, 0), (1, 0), (1, 0))).cumsum(axis=1).cumsum(axis=2)
    window_sq = sq[:, h:, w:] - sq[:, :-h, w:] - sq[:, h:, :-w] + sq[:, :-h, :-w]
    total = window_sq - 2 * cross + (g**2).sum()
    return np.maximum(total, 0.0) / (h * w * c)


def window_mse_torch(patch: np.ndarray, states):
    """`window_mse` in torch for states (B, C, H, W): (B, H - h + 1, W - w + 1), by
    convolutions (the cross term with the patch, the window sums of squares with ones)."""
    import torch
    import torch.nn.functional as F

    from afford.images import to_chw

    g = to_chw(patch).to(dtype=states.dtype, device=states.device)
    c, h, w = g.shape
    if states.shape[1] != c:
        raise GoalError(f"goal patch has {c} channels but the states have {states.shape[1]}")
    cross = F.conv2d(states, g[None])[:, 0]
    window_sq = F.conv2d((states**2).sum(1, keepdim=True), torch.ones_like(g[:1])[None])[:, 0]
    return (window_sq - 2 * cross + (g**2).sum()).clamp_min(0.0) / (h * w * c)
