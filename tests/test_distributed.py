"""`afford train` under torchrun: rank slices, the global batch, rank-0 writing, resumption."""

import json
import os
import signal
import subprocess
import sys
import time

import pytest
from torch.utils.data import RandomSampler

from afford.training.distributed import DistributedError, RankSlice, World, rank_batch, rank_threads


def test_rank_slices_are_disjoint_equal_and_share_one_order():
    import torch

    def base():  # every rank builds the same seeded sampler
        return RandomSampler(range(11), generator=torch.Generator().manual_seed(4))

    slices = [list(RankSlice(base(), World(rank=r, size=3))) for r in range(3)]
    assert [len(s) for s in slices] == [3, 3, 3] == [len(RankSlice(base(), World(r, 3))) for r in range(3)]
    order = list(base())
    assert sorted(sum(slices, [])) == sorted(order[:9])  # one order, cut to a multiple of 3
    assert slices[1] == order[1:9:3]


def test_the_preset_batch_is_split_over_the_ranks():
    assert rank_batch(32, World(0, 2)) == 16 and rank_batch(32, World()) == 32
    with pytest.raises(DistributedError, match="does not split evenly"):
        rank_batch(32, World(0, 3))
    assert rank_threads(2, World(0, 2, local_size=2)) == 1 and rank_threads(2, World()) == 2


def _torchrun(args: list[str], **kw) -> subprocess.Popen:
    cmd = [sys.executable, "-m", "torch.distributed.run", "--standalone", "--nproc_per_node", "2"]
    cmd += ["-m", "afford.cli.main", *args]
    return subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, **kw)


def _children(pid: int) -> list[int]:
    """torchrun puts each rank in a session of its own: its ranks are found as its children."""
    found = []
    for task in os.listdir(f"/proc/{pid}/task"):
        found += [int(c) for c in open(f"/proc/{pid}/task/{task}/children").read().split()]
    return found


@pytest.mark.slow
@pytest.mark.parametrize("net", ["recognition", "prediction"])
def test_torchrun_trains_on_two_ranks_and_rank_0_alone_writes(net, small_dataset, tmp_path):
    run = tmp_path / "run"
    args = ["train", net, "--data", str(small_dataset), "--preset", "tiny", "--out", str(run)]
    job = _torchrun([*args, "--set", "log_every=5"])
    out, err = job.communicate(timeout=300)
    assert job.returncode == 0, err[-3000:]
    assert out.count(f"{run}: 20 steps") == 1  # one rank prints
    records = [json.loads(line) for line in (run / "log.jsonl").read_text().splitlines()]
    steps = [r["step"] for r in records if "train/loss" in r]
    assert steps == sorted(set(steps)) and steps  # one writer: no step logged twice
    assert (run / "last.safetensors").is_file() and (run / "curves.png").is_file()


@pytest.mark.slow
def test_a_torchrun_run_killed_mid_way_resumes_from_its_checkpoint(small_dataset, tmp_path):
    run = tmp_path / "run"
    args = ["train", "recognition", "--data", str(small_dataset), "--preset", "tiny", "--out", str(run)]
    args += ["--steps", "4000", "--set", "eval_every=5", "--json"]
    job = _torchrun(args)
    deadline = time.monotonic() + 120
    try:
        while not (run / "last.safetensors").is_file() and time.monotonic() < deadline:
            assert job.poll() is None, job.communicate()[1][-3000:]
            time.sleep(0.2)
        time.sleep(1.0)
        for pid in [*_children(job.pid), job.pid]:  # every rank and torchrun, as a lost node would
            os.kill(pid, signal.SIGKILL)
        job.communicate(timeout=60)
    finally:
        job.kill()
    from afford.training.checkpoint import read_checkpoint

    reached = read_checkpoint(run / "last.safetensors", "recognition")[1]["step"]
    assert 5 <= reached < 4000
    args[args.index("4000")] = str(reached + 10)
    again = _torchrun(args)
    out, err = again.communicate(timeout=300)
    assert again.returncode == 0, err[-3000:]
    assert json.loads(out)["steps"] == reached + 10
    steps = [json.loads(line)["step"] for line in (run / "log.jsonl").read_text().splitlines()]
    assert max(steps) == reached + 10


def test_batches_and_targets_move_whole_to_the_device():
    import torch

    from afford.recognition.targets import Targets
    from afford.training.distributed import to_device

    t = Targets(*(torch.zeros(2, 3) for _ in range(4)))
    moved = to_device((torch.ones(2), [torch.ones(1), torch.ones(3)], t, 7), "cpu")
    assert isinstance(moved, tuple) and isinstance(moved[1], list) and isinstance(moved[2], Targets)
    assert moved[3] == 7 and moved[2].reg_mask.shape == (2, 3)


def test_a_gpu_asked_for_where_torch_sees_none_is_refused_in_one_line(small_dataset, tmp_path, capsys):
    import torch

    from afford.cli.main import main
    from afford.training.distributed import resolve_device

    if torch.cuda.is_available():
        pytest.skip("this machine has a GPU")
    assert resolve_device("auto") == "cpu" and resolve_device("cpu") == "cpu"
    args = ["train", "recognition", "--data", str(small_dataset), "--preset", "tiny", "--out", str(tmp_path)]
    assert main([*args, "--device", "cuda"]) == 2
    err = capsys.readouterr().err
    assert "--device cuda" in err and err.count("\n") == 1
