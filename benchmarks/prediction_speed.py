"""Prediction training speed for both presets, and the paper preset's projected 1 M batches.

    python benchmarks/prediction_speed.py [--threads 2] [--json]

Batches of 32 runs of 4 steps (the longest a training batch pads to), random data.
"""

from __future__ import annotations

import argparse
import json
import time

import torch

from afford.prediction.config import PRESETS
from afford.prediction.model import PredictionNet
from afford.prediction.train import make_optimizer, sequence_loss

PAPER_BATCHES = 1_000_000


def batches_per_second(preset: str, repeats: int) -> tuple[float, int]:
    config = PRESETS[preset]
    net = PredictionNet(config)
    opt = make_optimizer(net, config)
    b = config.batch_size
    images = torch.rand(b, 5, 4, 128, 128)
    actions = torch.rand(b, 4, 7)
    actions[..., 0] = torch.randint(0, 3, (b, 4)).float()
    steps = torch.full((b,), 4)
    sequence_loss(net, images, actions, steps).backward()  # warm-up
    t = time.perf_counter()
    for _ in range(repeats):
        loss = sequence_loss(net, images, actions, steps)
        opt.zero_grad()
        loss.backward()
        opt.step()
    return repeats / (time.perf_counter() - t), sum(p.numel() for p in net.parameters())


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--json", action="store_true")
    args = ap.parse_args()
    torch.set_num_threads(args.threads)
    result = {"threads": args.threads}
    for preset in ("cpu", "paper"):
        rate, params = batches_per_second(preset, args.repeats)
        result[preset] = {"parameters": params, "batches_per_second": round(rate, 3)}
    result["paper"]["projected_hours_for_1M_batches"] = round(
        PAPER_BATCHES / result["paper"]["batches_per_second"] / 3600, 1
    )
    if args.json:
        print(json.dumps(result, indent=2))
        return
    for preset in ("cpu", "paper"):
        r = result[preset]
        print(
            f"prediction {preset:5s} ({r['parameters']:,} parameters): "
            f"{r['batches_per_second']:.2f} batches/s"
        )
    print(
        f"paper preset, 1 M batches (the paper's schedule) on {args.threads} threads: "
        f"{result['paper']['projected_hours_for_1M_batches']:.0f} h"
    )


if __name__ == "__main__":
    main()
