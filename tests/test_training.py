"""Training and evaluation end to end on a small real dataset: resumption, checkpoints, CLI."""

from __future__ import annotations

import json

import pytest

from afford.cli.main import main


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
    assert "test" in result and "train" in result


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


def test_sigterm_saves_a_checkpoint_and_resume_continues(small_dataset, tmp_path):
    import signal
    import subprocess
    import sys
    import time

    run = tmp_path / "run"
    cmd = [sys.executable, "-m", "afford.cli.main", "train", "recognition", "--data", str(small_dataset)]
    cmd += ["--preset", "tiny", "--out", str(run), "--threads", "1", "--steps", "100000"]
    proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    deadline = time.time() + 120
    while not (run / "log.jsonl").exists() and time.time() < deadline:
        time.sleep(0.1)
    time.sleep(1.0)
    proc.send_signal(signal.SIGTERM)
    out, _ = proc.communicate(timeout=60)
    assert proc.returncode == 130 and b"run the same command again" in out
    from afford.training.checkpoint import read_checkpoint

    _, meta = read_checkpoint(run / "last.safetensors", "recognition")
    assert meta["step"] > 0


def test_keep_freed_memory_applies_on_glibc():
    import platform

    from afford.training.memory import keep_freed_memory

    applied = keep_freed_memory()
    if platform.system() == "Linux" and platform.libc_ver()[0] == "glibc":
        assert applied
