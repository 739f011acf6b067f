"""How likely each outcome is: the dynamics' outcome head, calibrated by one temperature.

The head is trained to pick the outcome the winner-takes-all loss gave the execution, and the
longer it trains the surer it grows: the shipped net's outcomes said 0.97 where 0.88 came
true, and 0.03 where 0.12 did. A planner that weighs outcomes by their probability (`--outcomes
expected`, risk) needs them as they come, so the head's logits are divided by a temperature T
fitted on a val split by maximum likelihood, against the same truth the measure uses: each
outcome's share in being the one nearest to what happened (`measure.nearest_share`).
Executions whose outcomes all predict the same leave T alone, as they leave the measure.
One number keeps the outcomes' order, so the likeliest outcome, and every pixel error, stay.

The net's config keeps T (`DynamicsConfig.outcome_temperature`); `dynamics.predict` applies it.
"""

from __future__ import annotations

import json
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np

from afford.objects.dynamics import ObjectDynamics
from afford.objects.measure import nearest_share, predict_all
from afford.objects.transitions import Transitions

CALIBRATION_FILE = "calibration.json"  # in a training run, written when `afford train dynamics` ends
LOG_T = np.linspace(np.log(0.25), np.log(8.0), 401)  # the temperatures tried: 0.25 to 8


@dataclass
class TemperatureFit:
    """The temperature fitted, the executions it was fitted on, their log-loss before and after
    (None where no execution's outcomes differ), and the training step of the checkpoint it
    was fitted to (a later checkpoint of the run is not calibrated by it)."""

    outcome_temperature: float
    executions: int
    nll_raw: float | None
    nll_calibrated: float | None
    step: int = -1


def logits_and_shares(net: ObjectDynamics, t: Transitions) -> tuple[np.ndarray, np.ndarray]:
    """(N, K) the head's logits (at temperature 1) and (N, K) each outcome's nearest share, for
    the executions of `t` whose outcomes differ."""
    outcomes = predict_all(net.outcomes, t)
    # softmax(z / T) = p, so z = T log p up to a constant per execution, which softmax ignores
    logits = np.log(np.clip(outcomes.probability, 1e-12, 1.0)) * net.config.outcome_temperature
    shares = np.stack(
        [nearest_share(t.after[i], outcomes.poses[i], ~np.isnan(t.before[i, :, 0])) for i in range(len(t))]
    )
    differ = shares.min(1) < shares.max(1)
    return logits[differ], shares[differ]


def log_loss(logits: np.ndarray, shares: np.ndarray, temperature: float) -> float:
    """The mean cross-entropy of softmax(logits / T) against the nearest shares."""
    z = logits / temperature
    z = z - z.max(1, keepdims=True)
    log_p = z - np.log(np.exp(z).sum(1, keepdims=True))
    return float(-(shares * log_p).sum(1).mean())


def fit_temperature(logits: np.ndarray, shares: np.ndarray) -> TemperatureFit:
    """The temperature of least log-loss on a grid (one parameter: a grid is exact enough and
    cannot diverge)."""
    if len(logits) == 0:  # a net of one outcome, or outcomes that never differ: nothing to fit
        return TemperatureFit(1.0, 0, None, None)
    losses = [log_loss(logits, shares, float(np.exp(lt))) for lt in LOG_T]
    best = float(np.exp(LOG_T[int(np.argmin(losses))]))
    return TemperatureFit(round(best, 4), len(logits), log_loss(logits, shares, 1.0), min(losses))


def write_calibration(run: str | Path, fit: TemperatureFit) -> Path:
    """RUN/calibration.json, which `read_calibration` and export read."""
    path = Path(run) / CALIBRATION_FILE
    path.write_text(json.dumps(asdict(fit), indent=2) + "\n")
    return path


def read_calibration(run: str | Path, step: int | None = None) -> dict:
    """The config fields a run's calibration sets, for `afford weights export` and loading a
    run's checkpoint: {} if it has none, or (with `step`) if it was fitted to another step's."""
    path = Path(run) / CALIBRATION_FILE
    if not path.is_file():
        return {}
    fit = json.loads(path.read_text())
    if step is not None and fit.get("step") != step:
        return {}
    return {"outcome_temperature": fit["outcome_temperature"]}
