"""How sure a prediction is, per pixel: a variance beside D's image (paper V, ours).

Section V of the paper leaves actions with uncertain outcomes to "a more principled approach".
One image per step cannot say that a cup placed at a block's end may stay or fall: the image
hedges, and eq. (5) scores the hedge as if it were certain. Here D's last features also give
log sigma^2 per pixel: the expected squared error of the state it draws there, one value for
the pixel's RGBD channels. It is trained by the beta-NLL loss of Seitzer et al. (2022): the
Gaussian negative log-likelihood weighted per pixel by sigma^(2 beta), held fixed, so that
pixels with a large error are not simply given a large variance and forgotten (beta 0.5).
The image is held fixed in this term: the mean learns exactly as without the head.

A net that draws two outcomes per step (a canonical one and a side effect, with a head that says
how likely each is) says how unsure it is without a head of its own: the state it carries on is
one outcome, and the truth is each outcome with the head's probability, so its expected squared
error per pixel is the probability-weighted squared distance of the outcomes from the one drawn
(`outcome_variance`).

An ensemble's members each give a mean and a variance; the state's variance is the mean of
the members' variances plus the variance of their means (the law of total variance, as PETS,
Chua et al. 2018).
"""

from __future__ import annotations

import torch
from torch import nn

# log sigma^2 lies in this range (a sigmoid squashes the head's output into it): sigma from
# 0.002 (an untouched background pixel) to 1.6 (anything at all).
LOG_VARIANCE_RANGE = (-12.0, 1.0)
# Where the head starts: sigma^2 = e^-7, about the squared error of a well-predicted pixel.
LOG_VARIANCE_START = -7.0


class VarianceHead(nn.Module):
    """log sigma^2 (B, drawn, H, W) from D's last features (B, width, H/2, W/2), each feature
    cell giving its 2 x 2 pixels as D's image does."""

    def __init__(self, width: int, drawn: int, act: type[nn.Module]):
        super().__init__()
        self.net = nn.Sequential(nn.Conv2d(width, width, 3, 1, 1), act(), nn.Conv2d(width, 4 * drawn, 1))
        lo, hi = LOG_VARIANCE_RANGE
        start = (LOG_VARIANCE_START - lo) / (hi - lo)
        with torch.no_grad():
            self.net[-1].weight.mul_(0.1)
            self.net[-1].bias.fill_(float(torch.logit(torch.tensor(start))))

    def forward(self, features: torch.Tensor) -> torch.Tensor:
        lo, hi = LOG_VARIANCE_RANGE
        raw = nn.functional.pixel_shuffle(self.net(features), 2)
        return lo + (hi - lo) * torch.sigmoid(raw)


def beta_nll(
    mean: torch.Tensor, log_variance: torch.Tensor, truth: torch.Tensor, beta: float
) -> torch.Tensor:
    """The beta-NLL per pixel (..., H, W) of a mean image (..., C, H, W) with one log variance
    per pixel (..., 1, H, W) against the truth: sum over channels of 0.5 log sigma^2 +
    (truth - mean)^2 / (2 sigma^2), weighted by sigma^(2 beta) without its gradient. The mean
    gets no gradient: only the variance learns from this term."""
    squared = ((truth - mean.detach()) ** 2).sum(-3)
    log_var = log_variance.squeeze(-3)
    channels = mean.shape[-3]
    nll = 0.5 * (channels * log_var + squared * torch.exp(-log_var))
    return torch.exp(beta * log_var).detach() * nll


def total_variance(means: torch.Tensor, variances: torch.Tensor) -> torch.Tensor:
    """The variance of a state per pixel from K members' means (K, ..., C, H, W) and variances
    (K, ..., H, W): the mean of the variances plus the variance of the means (averaged over the
    channels), the law of total variance. Zero where the members agree and are sure."""
    return variances.mean(0) + means.var(0, unbiased=False).mean(-3)


def outcome_variance(
    candidates: torch.Tensor, probability: torch.Tensor, drawn: torch.Tensor
) -> torch.Tensor:
    """Per pixel (..., H, W), the expected squared distance (averaged over the channels) of a
    net's K outcomes (..., K, C, H, W), weighed by their probabilities (..., K), from the image
    it drew (..., C, H, W): zero when it is sure or its outcomes agree."""
    squared = ((candidates - drawn.unsqueeze(-4)) ** 2).mean(-3)
    return (probability[..., None, None] * squared).sum(-3)
