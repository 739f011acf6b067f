"""A config's fields by name (training/fields.py): grouped records, flat names, stored dicts."""

from __future__ import annotations

import dataclasses
import json

import pytest

from afford.prediction.config import PRESETS, PredictionConfig
from afford.recognition.config import PRESETS as RECOGNITION
from afford.training.fields import flat, flat_names, from_dict, merged, paths, with_fields
from afford.training.overrides import apply_overrides

TWO = PRESETS["cpu-two-outcome"]


@dataclasses.dataclass(frozen=True)
class _Schedule:
    lr: float = 1.0


@dataclasses.dataclass(frozen=True)
class _Clash:  # two groups whose fields share a flat name
    first: _Schedule = _Schedule()
    second: _Schedule = _Schedule()


def _legacy(config: PredictionConfig) -> dict:
    """The config as files stored it before its fields were grouped: one flat dict."""
    by_path = {path: name for name, path in paths(PredictionConfig).items() if "." not in name}
    return {by_path[tuple(k.split("."))]: v for k, v in json.loads(json.dumps(flat(config))).items()}


def test_every_field_has_one_flat_name_and_one_path():
    names = flat_names(PredictionConfig)
    assert len(names) == len(flat(PredictionConfig())) == len(set(names))
    assert paths(PredictionConfig)["lr"] == paths(PredictionConfig)["training.lr"] == ("training", "lr")
    assert paths(PredictionConfig)["loss_l1"] == ("loss", "l1") and "l1" not in names


def test_a_stored_config_reads_back_the_same_whether_grouped_or_flat():
    grouped = json.loads(json.dumps(dataclasses.asdict(TWO)))
    assert from_dict(PredictionConfig, grouped) == TWO
    assert from_dict(PredictionConfig, _legacy(TWO)) == TWO
    # Keys afford no longer (or not yet) knows are ignored, as files from other versions hold.
    assert from_dict(PredictionConfig, {**_legacy(TWO), "retired_knob": 3}) == TWO
    assert from_dict(type(RECOGNITION["cpu"]), dataclasses.asdict(RECOGNITION["cpu"])) == RECOGNITION["cpu"]


def test_fitted_values_go_into_the_group_that_holds_them():
    stored = dataclasses.asdict(TWO)
    out = merged(PredictionConfig, stored, {"choice_scale": 0.5, "loss_l1": 3.0})
    assert out["outcomes"]["choice_scale"] == 0.5 and out["loss"]["l1"] == 3.0
    assert "choice_scale" not in out and "loss_l1" not in out
    assert stored["outcomes"]["choice_scale"] == 1.0  # the stored dict is left as it was
    flat_out = merged(PredictionConfig, _legacy(TWO), {"outcomes.choice_scale": 0.5})
    assert flat_out["choice_scale"] == 0.5 and "outcomes" not in flat_out
    assert from_dict(PredictionConfig, out).outcomes.choice_scale == 0.5
    with pytest.raises(TypeError, match="no field 'l1'"):
        merged(PredictionConfig, stored, {"l1": 3.0})


def test_set_names_a_field_by_its_flat_name_or_its_path():
    by_path = apply_overrides(TWO, ["training.lr=3e-4", "loss.l1=2", "outcomes.fork=decoder"])
    by_name = apply_overrides(TWO, ["lr=3e-4", "loss_l1=2", "fork=decoder"])
    assert by_path == by_name == with_fields(TWO, lr=3e-4, loss_l1=2.0, fork="decoder")
    assert (by_name.training.lr, by_name.loss.l1, by_name.outcomes.fork) == (3e-4, 2.0, "decoder")
    assert by_name.model == TWO.model and by_name.sampling == TWO.sampling


def test_a_name_no_field_goes_by_is_refused():
    with pytest.raises(TypeError, match="no field 'l1'"):
        with_fields(TWO, l1=2.0)
    with pytest.raises(TypeError, match="two fields go by the name 'lr'"):
        paths(_Clash)
