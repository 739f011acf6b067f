"""`--set KEY=VALUE` config overrides."""

from __future__ import annotations

import pytest

from afford.prediction.config import PRESETS as PREDICTION
from afford.recognition.config import PRESETS as RECOGNITION
from afford.training.overrides import OverrideError, apply_overrides


def test_values_take_the_fields_types():
    c = apply_overrides(
        PREDICTION["cpu"], ["lr=3e-4", "angle_flip=false", "steps=10", "encoder_channels=8, 16,16"]
    )
    assert (c.training.lr, c.sampling.angle_flip, c.training.steps, c.model.encoder_channels) == (
        3e-4,
        False,
        10,
        (8, 16, 16),
    )
    r = apply_overrides(RECOGNITION["cpu"], ["type_weights=1,1,3"])
    assert r.type_weights == (1.0, 1.0, 3.0)
    assert apply_overrides(RECOGNITION["cpu"], None) is RECOGNITION["cpu"]


@pytest.mark.parametrize("pair", ["nope=1", "lr", "steps=ten", "angle_flip=maybe"])
def test_bad_overrides_name_the_problem(pair):
    with pytest.raises(OverrideError, match="--set"):
        apply_overrides(PREDICTION["cpu"], [pair])
