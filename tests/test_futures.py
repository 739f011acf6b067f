"""Future-affordance recall (`afford eval futures`) on a small real dataset, shipped weights."""

from __future__ import annotations

import json

import pytest
import torch

from afford.cli.main import main
from afford.data.format import Dataset
from afford.planning.learned import load_learned
from afford.prediction.futures import BASELINES, future_recall


@pytest.fixture(scope="module")
def recognizer():
    return load_learned()[0]


def test_a_prediction_equal_to_the_truth_scores_like_the_truth(small_dataset, recognizer):
    result = future_recall(BASELINES["truth"], recognizer, Dataset(small_dataset), "train")
    assert result  # at least one step
    for row in result.values():
        assert row["predicted"] == row["true"]
        assert row["true"]["recall"]["all"]["hits"] > 0


def test_a_blank_prediction_finds_nothing(small_dataset, recognizer):
    def blank(images, actions, steps):
        return torch.zeros_like(images[:, 1:])

    result = future_recall(blank, recognizer, Dataset(small_dataset), "train")
    for row in result.values():
        assert row["predicted"]["recall"]["all"]["hits"] == 0
        assert row["true"]["recall"]["all"]["hits"] > 0


def test_eval_futures_cli(small_dataset, tmp_path, capsys):
    out = tmp_path / "futures"
    assert main(["eval", "futures", "--data", str(small_dataset), "--out", str(out), "--json"]) == 0
    report = json.loads(capsys.readouterr().out)
    assert set(report) >= {"net", "copy", "pictures"}
    assert report["net"]["1"]["true"]["recall"]["all"]["total"] > 0
    assert all((out / "futures" / p.split("/")[-1]).is_file() for p in report["pictures"])
    assert main(["eval", "futures", "--data", str(tmp_path / "none")]) == 2
