"""Training and evaluation end to end on a small real dataset: resumption, checkpoints, CLI."""

from __future__ import annotations

import json

import numpy as np
import pytest
import torch

from afford.cli.main import main
from afford.training.fields import with_fields


@pytest.mark.slow
@pytest.mark.parametrize("net", ["recognition", "prediction"])
def test_train_resumes_and_evaluates(net, small_dataset, tmp_path, capsys):
    run = tmp_path / net
    base = [
        "train",
        net,
        "--data",
        str(small_dataset),
        "--preset",
        "tiny",
        "--out",
        str(run),
        "--threads",
        "1",
    ]
    assert main([*base, "--steps", "10", "--json"]) == 0
    first = json.loads(capsys.readouterr().out)
    assert first["steps"] == 10
    assert (run / "last.safetensors").is_file() and (run / "curves.png").is_file()
    assert list((run / "tensorboard").iterdir())
    # The same command with more steps continues from step 10, as after a kill.
    assert main([*base, "--steps", "20", "--json"]) == 0
    second = json.loads(capsys.readouterr().out)
    assert second["steps"] == 20
    steps = [json.loads(line)["step"] for line in (run / "log.jsonl").read_text().splitlines()]
    assert steps == sorted(steps) and steps[-1] == 20
    assert main(["eval", net, "--run", str(run), "--data", str(small_dataset), "--json"]) == 0
    result = json.loads(capsys.readouterr().out)
    from afford.data.format import Dataset

    test_states = sum(seq.length + 1 for seq in Dataset(small_dataset).sequences("test"))
    if net == "recognition":  # Table 1: counts that add up, on every test state
        table = result["test"]
        assert table["images"] == test_states and table["spurious_per_image"] >= 0
        for row in table["recall"].values():
            assert 0 <= row["hits"] <= row["total"] and row["recall"] == pytest.approx(
                row["hits"] / row["total"]
            )
        assert table["recall"]["all"]["total"] == sum(
            table["recall"][t]["total"] for t in ("grasp", "place", "turn")
        )
    else:  # Table 2: each step's error over every test transition, the copy baseline beside it
        transitions = sum(seq.length for seq in Dataset(small_dataset).sequences("test"))
        for split in ("test", "test_copy"):
            rows = result[split]
            assert rows["all"]["all_area"]["n"] == transitions
            assert sum(r["all_area"]["n"] for k, r in rows.items() if k != "all") == transitions
            for row in rows.values():
                # A split with no step of a kind (here: no side effect) has no figure for it.
                assert all(row[m]["n"] == 0 or 0 <= row[m]["mean"] < 1 and row[m]["sd"] >= 0 for m in row)
                canonical, side = row["changed_area_canonical"]["n"], row["changed_area_side"]["n"]
                assert canonical + side == row["changed_area"]["n"]
        foresight = result["foresight"]
        assert foresight["acted"]["all"]["executions"] == transitions
        copy = result["test_copy"]["all"]
        # Copying errs only where the truth changed: the changed area's mean error is the larger.
        assert 0 < copy["all_area"]["mean"] < copy["changed_area_any"]["mean"]


def test_resume_with_another_architecture_is_one_line(small_dataset, tmp_path, capsys):
    run = tmp_path / "run"
    base = [
        "train",
        "recognition",
        "--data",
        str(small_dataset),
        "--out",
        str(run),
        "--threads",
        "1",
        "--steps",
        "2",
    ]
    assert main([*base, "--preset", "tiny"]) == 0
    capsys.readouterr()
    assert main([*base, "--preset", "cpu"]) == 2
    assert "architecture differs" in capsys.readouterr().err


def test_eval_of_a_missing_run(small_dataset, tmp_path, capsys):
    assert main(["eval", "recognition", "--run", str(tmp_path / "none"), "--data", str(small_dataset)]) == 2
    assert "no such run" in capsys.readouterr().err


@pytest.mark.slow
@pytest.mark.parametrize("net, to_group", [("recognition", False), ("prediction", True)])
def test_sigterm_saves_a_checkpoint_and_resume_continues(net, to_group, small_dataset, tmp_path):
    """SIGTERM to the trainer, or to its whole process group with a batch-loading worker in it
    (as `pkill -f` or Ctrl-C in a terminal would): a checkpoint is saved either way."""
    import os
    import signal
    import subprocess
    import sys
    import time

    run = tmp_path / "run"
    cmd = [sys.executable, "-m", "afford.cli.main", "train", net, "--data", str(small_dataset)]
    cmd += ["--preset", "tiny", "--out", str(run), "--threads", "1", "--steps", "100000"]
    if to_group:
        cmd += ["--set", "loader_workers=1"]
    proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, start_new_session=to_group)
    log = run / "log.jsonl"
    deadline = time.time() + 120
    # Wait for the first logged training step (an event, not a guess of how long it takes).
    while not (log.exists() and '"train/loss"' in log.read_text()) and time.time() < deadline:
        time.sleep(0.05)
    assert log.exists(), "training logged no step in time"
    if to_group:
        os.killpg(proc.pid, signal.SIGTERM)
    else:
        proc.send_signal(signal.SIGTERM)
    out, err = proc.communicate(timeout=60)
    assert proc.returncode == 130 and b"run the same command again" in out, err.decode()[-500:]
    from afford.training.checkpoint import read_checkpoint

    _, meta = read_checkpoint(run / "last.safetensors", net)
    assert meta["step"] > 0


def test_keep_freed_memory_applies_where_glibc_is_and_nowhere_else():
    import platform

    from afford.training.memory import keep_freed_memory

    glibc = platform.system() == "Linux" and platform.libc_ver()[0] == "glibc"
    assert keep_freed_memory() == glibc


def test_the_samplers_draw_the_asked_share_of_turn_and_side_effect_sequences(small_dataset):
    from afford.data.effects import sequence_effects
    from afford.data.format import Dataset
    from afford.data.torch_data import PredictionData
    from afford.prediction.config import PRESETS
    from afford.prediction.train import run_sampler

    data = Dataset(small_dataset)
    indices = [i for i in data.indices() if data.sequence(i).length > 0]  # every split: both kinds
    part = PredictionData(data, "train")
    part.indices = indices
    labels = {i: sequence_effects(data.sequence(i)) for i in indices}
    placed = {i: any(s.type == "place" and not s.canonical for s in labels[i]) for i in indices}
    truth = {
        "turn": np.array([any(s.type == "turn" for s in labels[i]) for i in indices]),
        "effect": np.array([any(not s.canonical for s in labels[i]) for i in indices]),
        "place_effect": np.array([placed[i] for i in indices]),
    }
    for what, flagged in truth.items():
        assert flagged.any() and not flagged.all(), what  # the small dataset holds each kind
        config = with_fields(PRESETS["tiny"], **{f"{what}_fraction": 0.7})
        weights = run_sampler([part], config, seed=0).weights.numpy()
        assert weights[flagged].sum() == pytest.approx(0.7) and weights.sum() == pytest.approx(1.0)
        # Two datasets joined: the share holds over the runs of both, in their order.
        joined = run_sampler([part, part], config, seed=0).weights.numpy()
        assert joined[np.concatenate([flagged, flagged])].sum() == pytest.approx(0.7)
        with pytest.raises(ValueError, match="between 0 and 1"):
            run_sampler([part], with_fields(config, **{f"{what}_fraction": 1.5}), seed=0)
    assert run_sampler([part], PRESETS["tiny"], seed=0) is None
    # Both asked: each kind gets at least its share, the rest comes from sequences with neither.
    both = with_fields(PRESETS["tiny"], turn_fraction=0.3, effect_fraction=0.4)
    weights = run_sampler([part], both, seed=0).weights.numpy()
    neither = ~(truth["turn"] | truth["effect"])
    assert weights.sum() == pytest.approx(1.0) and weights[neither].sum() == pytest.approx(0.3)
    assert weights[truth["turn"]].sum() >= 0.3 - 1e-9 and weights[truth["effect"]].sum() >= 0.4 - 1e-9
    # Places with a side effect on top of side effects: a floor within a floor.
    nested = with_fields(PRESETS["tiny"], effect_fraction=0.5, place_effect_fraction=0.2)
    weights = run_sampler([part], nested, seed=0).weights.numpy()
    assert weights[~truth["effect"]].sum() == pytest.approx(0.3)
    assert weights[truth["place_effect"]].sum() >= 0.2 - 1e-9
    with pytest.raises(ValueError, match="sum below 1"):
        run_sampler([part], with_fields(PRESETS["tiny"], turn_fraction=0.5, effect_fraction=0.5), seed=0)


def test_joined_datasets_give_every_run_of_each_and_their_own_streams(small_dataset):
    from afford.data.format import Dataset
    from afford.data.torch_data import JoinedData, PredictionData

    data = Dataset(small_dataset)
    first, second = (
        PredictionData(data, "train", random_start=False),
        PredictionData(data, "val", random_start=False),
    )
    joined = JoinedData([first, second])
    assert len(joined) == len(first) + len(second)
    assert torch.equal(joined[len(first)][1], second[0][1])
    assert torch.equal(joined[len(first) - 1][1], first[len(first) - 1][1])
    joined.rng = np.random.default_rng(3)
    assert first.rng is not second.rng and first.rng.random() != second.rng.random()


def test_effect_masks_move_with_the_augmented_images(small_dataset):
    from afford.data.augment import AugmentConfig
    from afford.data.effects import sequence_effects, step_mask
    from afford.data.format import Dataset
    from afford.data.torch_data import PredictionData, collate_prediction

    data = Dataset(small_dataset)
    labelled = ((i, t, s) for i in data.indices() for t, s in enumerate(sequence_effects(data.sequence(i))))
    i, t, step = next((i, t, s) for i, t, s in labelled if not s.canonical)
    seq = data.sequence(i)
    expected = step_mask(step, seq.poses[t], seq.poses[t + 1], seq.actions[t])
    plain = PredictionData(data, "train", random_start=False, effect_masks=True)
    plain.indices = [i]
    images, actions, effects = plain[0]
    assert effects.shape == (seq.length, *images.shape[2:]) and effects.dtype == torch.bool
    assert np.array_equal(effects[t].numpy(), expected) and expected.any()
    mirror = AugmentConfig(shift_px=0, mirror=True)
    mirrored = PredictionData(data, "train", augment_config=mirror, random_start=False, effect_masks=True)
    mirrored.indices = [i]
    while True:  # the mirror is drawn half the time
        m_images, _, m_effects = mirrored[0]
        if not torch.equal(m_images, images):
            break
    assert np.array_equal(m_effects[t].numpy(), expected[:, ::-1])
    batch = collate_prediction([plain[0], plain[0]])
    assert len(batch) == 4 and batch[3].shape == (2, seq.length, *images.shape[2:])


def test_recognition_runs_repeat_with_one_seed_and_differ_with_another(small_dataset, tmp_path):
    from safetensors.torch import load_file

    from afford.recognition.config import PRESETS
    from afford.recognition.train import train

    def weights(seed: int, name: str) -> dict[str, torch.Tensor]:
        config = with_fields(PRESETS["tiny"], steps=3, threads=1, seed=seed)
        train(small_dataset, config, tmp_path / name, progress=False)
        return load_file(tmp_path / name / "last.safetensors")

    first, again, other = weights(0, "a"), weights(0, "b"), weights(1, "c")
    shared = [k for k in first if first[k].is_floating_point()]
    assert all(torch.equal(first[k], again[k]) for k in shared)
    assert not all(torch.equal(first[k], other[k]) for k in shared)
