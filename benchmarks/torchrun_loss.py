"""torchrun against one process: the training loss over the first batches, and a resume.

    python benchmarks/torchrun_loss.py --data data/cpu [--net recognition] [--steps 200]
        [--out out/torchrun] [--json]

Trains the `cpu` preset for --steps batches three ways, each from the same initial weights
and at the same global batch: in one process; under `torchrun --standalone --nproc_per_node
2` (each rank half the batch); and under torchrun again, stopped by SIGTERM after its first
checkpoint (at half the steps) and started again, which must resume. Prints the mean loss
per window of batches for each and writes OUT/loss.png with the three curves. The two
processes see other batches than the one (each rank its own slice and augmentations), so
the curves agree within the noise of batch sampling, not exactly; the resumed run repeats the
other torchrun run exactly up to its checkpoint. Run it on an otherwise idle machine.
"""

from __future__ import annotations

import argparse
import json
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

WINDOW = 50  # batches per row of the table


def train(net: str, data: str, run: Path, steps: int, ranks: int, stop_at: int | None = None) -> float:
    """Wall seconds of one `afford train` (under torchrun when ranks > 1); `stop_at`: SIGTERM
    torchrun once a checkpoint past that step exists, then return."""
    cmd = [sys.executable, "-m", "afford.cli.main"]
    if ranks > 1:
        cmd = [sys.executable, "-m", "torch.distributed.run", "--standalone", f"--nproc_per_node={ranks}"]
        cmd += ["-m", "afford.cli.main"]
    cmd += ["train", net, "--data", data, "--preset", "cpu", "--out", str(run), "--steps", str(steps)]
    cmd += ["--set", "log_every=10", "--set", f"eval_every={steps // 2}", "--json"]
    t0 = time.perf_counter()
    job = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    if stop_at is not None:
        while job.poll() is None and not _checkpoint_reached(run, net, stop_at):
            time.sleep(0.5)
        job.send_signal(signal.SIGTERM)  # torchrun passes it to every rank; rank 0 saves
    _, err = job.communicate()
    if stop_at is None and job.returncode != 0:
        raise SystemExit(f"training failed: {err[-2000:]}")
    return time.perf_counter() - t0


def _checkpoint_reached(run: Path, net: str, step: int) -> bool:
    from afford.training.checkpoint import CheckpointError, read_checkpoint

    try:
        return read_checkpoint(run / "last.safetensors", net)[1]["step"] >= step
    except CheckpointError:
        return False


def losses(run: Path) -> dict[int, float]:
    rows = [json.loads(line) for line in (run / "log.jsonl").read_text().splitlines()]
    return {r["step"]: r["train/loss"] for r in rows if "train/loss" in r}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--data", required=True)
    ap.add_argument("--net", choices=["recognition", "prediction"], default="recognition")
    ap.add_argument("--steps", type=int, default=200)
    ap.add_argument("--out", default="out/torchrun")
    ap.add_argument("--json", action="store_true")
    args = ap.parse_args()
    out = Path(args.out)
    if out.exists():
        raise SystemExit(f"{out} exists: give another --out (the runs would resume)")
    seconds = {
        "1 process": train(args.net, args.data, out / "one", args.steps, 1),
        "torchrun 2": train(args.net, args.data, out / "two", args.steps, 2),
    }
    first = train(args.net, args.data, out / "resumed", args.steps, 2, stop_at=args.steps // 2)
    seconds["torchrun 2, killed + resumed"] = first + train(
        args.net, args.data, out / "resumed", args.steps, 2
    )
    curves = {
        "1 process": losses(out / "one"),
        "torchrun 2": losses(out / "two"),
        "torchrun 2, killed + resumed": losses(out / "resumed"),
    }
    windows = {}
    for name, curve in curves.items():
        steps = np.array(sorted(curve))
        values = np.array([curve[s] for s in steps])
        windows[name] = [
            round(float(values[(steps > a) & (steps <= a + WINDOW)].mean()), 4)
            for a in range(0, args.steps, WINDOW)
        ]
    result = {
        "net": args.net,
        "steps": args.steps,
        "window": WINDOW,
        "mean_loss_per_window": windows,
        "steps_per_second": {k: round(args.steps / v, 2) for k, v in seconds.items()},
        "picture": str(out / "loss.png"),
    }
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(7, 4))
    for name, curve in curves.items():
        ax.plot(sorted(curve), [curve[s] for s in sorted(curve)], label=name, alpha=0.8)
    ax.set(xlabel="batch (global batch of the preset)", ylabel="training loss", yscale="log")
    ax.set_title(f"{args.net}: one process vs torchrun --nproc_per_node 2")
    ax.legend()
    ax.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(out / "loss.png", dpi=110)
    if args.json:
        print(json.dumps(result, indent=2))
        return
    print(f"mean training loss per {WINDOW} batches ({args.net}, cpu preset, global batch as the preset's)")
    header = " ".join(f"{a + 1:>4}-{a + WINDOW:<4}" for a in range(0, args.steps, WINDOW))
    print(f"{'':30s} {header}   batches/s")
    for name, w in windows.items():
        rate = result["steps_per_second"][name]
        print(f"{name:30s} " + " ".join(f"{v:9.4f}" for v in w) + f"   {rate:.2f}")
    print(f"picture: {out / 'loss.png'}")


if __name__ == "__main__":
    from afford.errors import exit_on_user_error

    exit_on_user_error(main)
