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


def test_a_stored_field_this_code_does_not_vary_loads_at_its_value_and_refuses_any_other():
    """Shipped files store fields whose experiments left the code (PredictionConfig.removed):
    at the one value the code runs they load as before; another value is a net this afford
    cannot build or train as it was, and says so."""
    stored = {"variance": False, "fork_blocks": 1, "choice_head": "pooled", "lr": 1e-4}
    assert from_dict(PredictionConfig, stored) == with_fields(PredictionConfig(), lr=1e-4)
    assert from_dict(PredictionConfig, {"loss": {"nll": 0.0, "l1": 0.5}}).loss.l1 == 0.5
    for asks in ({"variance": True}, {"loss": {"nll": 1.0}}, {"choice_head": "grid"}, {"trained": "side"}):
        with pytest.raises(ValueError, match="does not hold"):
            from_dict(PredictionConfig, asks)
    from afford.objects.dynamics import DynamicsConfig
    from afford.objects.perception import PerceptionConfig

    stored = {"arm_path": False, "mirror": False, "rare_weight": 1.0}
    assert from_dict(DynamicsConfig, stored) == DynamicsConfig()
    assert from_dict(PerceptionConfig, {"hidden": False, "edge_weight": 1.0}) == PerceptionConfig()
    for cls, asks in ((DynamicsConfig, {"arm_path": True}), (PerceptionConfig, {"hidden": True})):
        with pytest.raises(ValueError, match="does not hold"):
            from_dict(cls, asks)


def test_a_checkpoint_asking_for_a_removed_feature_is_a_one_line_error(tmp_path):
    from afford.errors import UserError
    from afford.prediction.evaluate import load_net
    from afford.prediction.model import PredictionNet
    from afford.training.checkpoint import save_checkpoint

    stored = {**_legacy(PRESETS["tiny"]), "variance": True}
    save_checkpoint(tmp_path / "net.safetensors", PredictionNet(PRESETS["tiny"]), "prediction", stored, 0)
    with pytest.raises(UserError, match="variance=True"):
        load_net(tmp_path / "net.safetensors")
