"""Predicted states as recognition data (`afford data predict`, `--predicted`)."""

from __future__ import annotations

import json

import numpy as np
import torch

from afford.cli.main import main
from afford.data.format import Dataset
from afford.data.predicted import PredictedStates, mixed_sampler


def test_predict_writes_each_state_labelled_by_the_truth(small_dataset, tmp_path, capsys):
    out = tmp_path / "predicted.npz"
    assert main(["data", "predict", str(small_dataset), "--out", str(out), "--json"]) == 0
    record = json.loads(capsys.readouterr().out)
    data = Dataset(small_dataset)
    lengths = [data.sequence(i).length for i in data.indices("train")]
    assert record["states"] == sum(lengths) > 0
    states = PredictedStates(out, data)
    image, rows = states[0]
    assert image.shape == (4, 128, 128) and 0 <= float(image.min()) <= float(image.max()) <= 1
    seq, step = int(states.sequence[0]), int(states.step[0])
    assert step == 1  # a run's first prediction is of its state 1
    assert torch.equal(rows, torch.from_numpy(data.sequence(seq).affordances[step]))
    # the net drew the action's effect: not the start image copied
    assert not np.allclose(states.image(0), data.sequence(seq).image(0), atol=0.02)


def test_mixed_sampler_draws_the_asked_fraction():
    draws = torch.tensor(list(mixed_sampler(10_000, 300, 0.3, seed=1)))
    assert len(draws) == 10_000
    assert abs(float((draws >= 10_000).float().mean()) - 0.3) < 0.02


def test_predict_of_a_missing_dataset_is_one_line(tmp_path):
    assert main(["data", "predict", str(tmp_path / "none"), "--out", str(tmp_path / "p.npz")]) == 2
