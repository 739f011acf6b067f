"""Dynamics learned from the starts a planner gives them: the objects the shipped perception net
finds, at their true poses; what it misses, absent."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
import torch

from afford.data.generate import GenerateConfig, generate
from afford.objects.dynamics import PRESETS
from afford.objects.train import load_perceived, train
from afford.objects.transitions import read_transitions
from afford.shipped import OBJECTS, PERCEPTION_FILE
from afford.training.checkpoint import read_checkpoint

TINY = dataclasses.replace(PRESETS["tiny"], threads=1)
SHIPPED_PERCEPTION = OBJECTS / PERCEPTION_FILE


@pytest.fixture(scope="module")
def masked(tmp_path_factory):
    root = tmp_path_factory.mktemp("masked") / "m"
    generate(root, GenerateConfig(sequences=4, seed=7, workers=1, shard_size=4, masks=True), progress=False)
    return root


def test_perceived_starts_keep_true_poses_of_what_is_found(masked):
    truth = read_transitions(masked)
    seen = load_perceived([masked], SHIPPED_PERCEPTION, None)
    assert len(seen) == len(truth)
    found = ~np.isnan(seen.before[..., 0])
    # the shipped net finds most objects of these scenes, each at its true pose exactly
    assert found.sum() >= 0.8 * (~np.isnan(truth.before[..., 0])).sum()
    np.testing.assert_array_equal(seen.before[found], truth.before[found])
    # nothing is found that is not there, and the held object is kept where it was found
    assert not (found & np.isnan(truth.before[..., 0])).any()
    rows = np.arange(len(truth))
    kept = (truth.held_before >= 0) & found[rows, np.maximum(truth.held_before, 0)]
    np.testing.assert_array_equal(seen.held_before[kept], truth.held_before[kept])
    assert (seen.held_before[~kept] == -1).all()
    np.testing.assert_array_equal(seen.after, truth.after)


def test_a_batch_takes_its_share_from_the_perceived_executions():
    from afford.objects.train import batch_rows

    rows = batch_rows(np.random.default_rng(0), 100, 140, 64, 16)
    assert len(rows) == 64 and (rows[:48] < 100).all() and ((rows[48:] >= 100) & (rows[48:] < 140)).all()
    assert (batch_rows(np.random.default_rng(0), 100, 100, 64, 0) < 100).all()


def test_training_draws_a_share_of_each_batch_from_perceived_starts(masked, tmp_path):
    config = dataclasses.replace(TINY, perceived_share=0.5)
    run = tmp_path / "run"
    train([masked], config, run, progress=False, perceived_dirs=[masked], perception=SHIPPED_PERCEPTION)
    assert (run / "best.safetensors").is_file()
    assert f"{masked} (from perceived starts)" in (run / "data.txt").read_text()
    # a run that starts from those weights begins where they left off: with no step size,
    # it ends there too
    again = tmp_path / "again"
    still = dataclasses.replace(TINY, steps=1, lr=0.0)
    train([masked], still, again, progress=False, init=run / "best.safetensors")
    first, _ = read_checkpoint(run / "best.safetensors", "dynamics")
    then, _ = read_checkpoint(again / "last.safetensors", "dynamics")
    weights = [k for k in first if k.startswith("model.")]
    assert weights and all(torch.equal(first[k], then[k]) for k in weights)


def test_perception_training_goes_on_from_another_runs_weights(masked, tmp_path):
    from afford.objects.perception import PRESETS as SEEING
    from afford.objects.perception_train import train as train_perception

    tiny = dataclasses.replace(SEEING["tiny"], steps=2, eval_every=2, threads=1)
    first_run, again = tmp_path / "first", tmp_path / "again"
    train_perception(masked, tiny, first_run, progress=False)
    # with no step size, a run started from those weights ends with them (batch statistics
    # aside, which every training batch moves)
    train_perception(
        masked,
        dataclasses.replace(tiny, steps=1, lr=0.0),
        again,
        progress=False,
        init=first_run / "last.safetensors",
    )
    first, _ = read_checkpoint(first_run / "last.safetensors", "perception")
    then, _ = read_checkpoint(again / "last.safetensors", "perception")
    weights = [k for k in first if k.startswith("model.") and "running" not in k and "batches" not in k]
    assert weights and all(torch.equal(first[k], then[k]) for k in weights)
    fresh = tmp_path / "fresh"
    train_perception(masked, dataclasses.replace(tiny, steps=1, lr=0.0), fresh, progress=False)
    other, _ = read_checkpoint(fresh / "last.safetensors", "perception")
    assert not all(torch.equal(first[k], other[k]) for k in weights)
