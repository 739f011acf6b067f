"""`afford generate --ray`: the same bytes as local workers, and a worker killed mid-run."""

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
from conftest import SMALL_SEED, SMALL_SEQUENCES, SMALL_SHARD


@pytest.fixture
def ray():
    return pytest.importorskip("ray", reason="the cluster extra: pip install 'afford[cluster]'")


def _shard_bytes(root: Path) -> dict[str, bytes]:
    return {p.name: p.read_bytes() for p in sorted((root / "shards").glob("*.npz"))}


@pytest.mark.slow
def test_ray_on_a_local_instance_writes_the_same_shards_as_local_workers(ray, small_dataset, tmp_path):
    from afford.data.generate import GenerateConfig, generate

    config = GenerateConfig(
        sequences=SMALL_SEQUENCES, seed=SMALL_SEED, workers=2, shard_size=SMALL_SHARD, executor="ray"
    )
    report = generate(tmp_path / "ray", config, progress=False)
    assert report.made_shards == SMALL_SEQUENCES // SMALL_SHARD
    assert not ray.is_initialized()  # the instance it started is stopped
    ours, theirs = _shard_bytes(tmp_path / "ray"), _shard_bytes(small_dataset)
    assert ours.keys() == theirs.keys() and ours == theirs


def _parent(pid: int) -> int:
    return int(Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[1])


def _ray_shard_workers(ancestor: int) -> list[int]:
    """Pids of Ray worker processes running a shard now (Ray names them after the task) that
    descend from `ancestor` (a local instance's processes are its driver's children), so a
    test running beside this one keeps its workers."""
    pids = []
    for entry in Path("/proc").iterdir():
        try:
            if not (entry.name.isdigit() and (entry / "cmdline").read_bytes().startswith(b"ray::make_shard")):
                continue
            pid = int(entry.name)
            while pid > 1 and pid != ancestor:
                pid = _parent(pid)
            if pid == ancestor:
                pids.append(int(entry.name))
        except (OSError, ValueError, IndexError):
            pass
    return pids


@pytest.mark.slow
def test_a_ray_worker_killed_mid_run_still_gives_every_sequence(ray, tmp_path):
    from afford.data.format import Dataset, read_manifest, shard_status

    out, sequences = tmp_path / "data", 8
    cmd = [sys.executable, "-m", "afford.cli.main", "generate", "--out", str(out), "--json"]
    cmd += ["--sequences", str(sequences), "--shard-size", "2", "--seed", "5", "--ray", "--workers", "2"]
    job = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    killed, deadline = None, time.monotonic() + 120
    try:
        while killed is None and job.poll() is None and time.monotonic() < deadline:
            workers = _ray_shard_workers(job.pid)
            if workers:
                killed = workers[0]
                os.kill(killed, signal.SIGKILL)
            time.sleep(0.05)
        out_text, err_text = job.communicate(timeout=240)
    finally:
        job.kill()
    assert killed is not None, "no Ray worker was seen running a shard"
    assert job.returncode == 0, err_text.decode()[-2000:]
    manifest = read_manifest(out)
    present, missing = shard_status(out, manifest)
    assert not missing and not list((out / "shards").glob(".*.tmp"))
    data = Dataset(out)
    assert sum(1 for i in range(sequences) if data.sequence(i).index == i) == sequences
    verify = subprocess.run(
        [sys.executable, "-m", "afford.cli.main", "data", "verify", str(out)], capture_output=True, text=True
    )
    assert verify.returncode == 0, verify.stdout + verify.stderr


def test_the_core_install_never_imports_ray(tmp_path):
    code = (
        "import sys\n"
        "from afford.data.generate import GenerateConfig, generate\n"
        f"generate({str(tmp_path / 'd')!r}, GenerateConfig(sequences=1, seed=0, workers=1), progress=False)\n"
        "assert 'ray' not in sys.modules\n"
    )
    subprocess.run([sys.executable, "-c", code], check=True)


def test_without_ray_the_ray_executor_says_how_to_get_it(tmp_path):
    code = (
        "import sys\n"
        "sys.modules['ray'] = None  # as if the cluster extra were not installed\n"
        "from afford.cli.main import main\n"
        f"sys.exit(main(['generate', '--out', {str(tmp_path / 'd')!r}, '--sequences', '1', '--ray']))\n"
    )
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert r.returncode == 2 and "pip install 'afford[cluster]'" in r.stderr
    assert "Traceback" not in r.stderr
