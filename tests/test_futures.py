"""Evaluation with the shipped weights: future-affordance recall (`afford eval futures`) and
Table 1 at the shipped cut-off, on a small real dataset."""

from __future__ import annotations

import json

import pytest
import torch

from afford.cli.main import main
from afford.data.format import Dataset
from afford.prediction.futures import BASELINES, future_recall
from afford.shipped import Nets


@pytest.fixture(scope="module")
def recognizer():
    return Nets().recognizer


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


def test_eval_recognition_without_a_run_uses_the_shipped_cut_off(small_dataset, tmp_path, capsys, recognizer):
    out = tmp_path / "rec"
    assert main(["eval", "recognition", "--data", str(small_dataset), "--out", str(out), "--json"]) == 0
    report = json.loads(capsys.readouterr().out)
    assert report["threshold"] == recognizer.threshold and "val_sweep" not in report
    assert report["test"]["recall"]["all"]["total"] > 0 and (out / "table1.json").is_file()
