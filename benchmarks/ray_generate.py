"""Ray generation against local workers: the same bytes, executions/s, and a worker killed.

    python benchmarks/ray_generate.py [--sequences 100] [--workers 2] [--json]

Makes one dataset three times into a temporary folder with `afford generate`: with
`--workers N` (a local process pool), with `--ray --workers N` (a local Ray instance of N
CPUs), and with `--ray` again while one Ray worker is killed (SIGKILL) as soon as it runs a
shard. Prints executions/s of each (Ray's start-up included: it is part of what a user
waits for), whether every shard is byte-identical to the pool's, and whether the killed run
still holds every sequence and passes `afford data verify`. Needs the cluster extra
(`pip install 'afford[cluster]'`); run it on an otherwise idle machine.
"""

from __future__ import annotations

import argparse
import json
import os
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path


def afford(*args: str) -> list[str]:
    return [sys.executable, "-m", "afford.cli.main", *args]


def ray_shard_workers() -> list[int]:
    """Ray names a worker process after the task it runs."""
    pids = []
    for entry in Path("/proc").iterdir():
        try:
            if entry.name.isdigit() and (entry / "cmdline").read_bytes().startswith(b"ray::make_shard"):
                pids.append(int(entry.name))
        except OSError:
            pass
    return pids


def generate(out: Path, sequences: int, workers: int, ray: bool, kill: bool = False) -> dict:
    cmd = afford("generate", "--out", str(out), "--sequences", str(sequences), "--seed", "11")
    cmd += ["--workers", str(workers), "--shard-size", "5", "--json"] + (["--ray"] if ray else [])
    job = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    killed = None
    while kill and killed is None and job.poll() is None:
        found = ray_shard_workers()
        if found:
            killed = found[0]
            os.kill(killed, signal.SIGKILL)
        time.sleep(0.05)
    stdout, stderr = job.communicate()
    if job.returncode != 0:
        raise SystemExit(f"generate failed: {stderr[-2000:]}")
    # Ray may write a line of its own (a worker that died) before the record.
    start = stdout.find("{\n")
    if start < 0:
        raise SystemExit(f"generate printed no record: {stdout[-2000:]!r} {stderr[-2000:]!r}")
    report = json.loads(stdout[start:])
    report["killed_worker"] = killed
    return report


def shard_bytes(root: Path) -> dict[str, bytes]:
    return {p.name: p.read_bytes() for p in sorted((root / "shards").glob("*.npz"))}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--sequences", type=int, default=100)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--json", action="store_true")
    args = ap.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        runs = {
            "local pool": (Path(tmp) / "pool", False, False),
            "ray": (Path(tmp) / "ray", True, False),
            "ray, one worker killed": (Path(tmp) / "killed", True, True),
        }
        rows = {}
        for name, (out, ray, kill) in runs.items():
            r = generate(out, args.sequences, args.workers, ray, kill)
            verify = subprocess.run(afford("data", "verify", str(out)), capture_output=True, text=True)
            rows[name] = {
                "seconds": r["seconds"],
                "executions": r["executions_made"],
                "executions_per_second": r["executions_per_second"],
                "identical_to_pool": shard_bytes(out) == shard_bytes(runs["local pool"][0]),
                "verify_passes": verify.returncode == 0,
                "killed_worker": r["killed_worker"],
            }
    result = {"sequences": args.sequences, "workers": args.workers, "runs": rows}
    if args.json:
        print(json.dumps(result, indent=2))
        return
    for name, r in rows.items():
        kill = f"; worker {r['killed_worker']} killed" if r["killed_worker"] else ""
        print(
            f"{name:24s} {r['executions']} executions in {r['seconds']:6.1f} s = "
            f"{r['executions_per_second']:5.1f}/s; same bytes as the pool: {r['identical_to_pool']}; "
            f"verify: {'passes' if r['verify_passes'] else 'FAILS'}{kill}"
        )


if __name__ == "__main__":
    from afford.errors import exit_on_user_error

    exit_on_user_error(main)
