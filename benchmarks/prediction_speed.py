"""Prediction training speed: batches/s per preset, where a training step's time goes.

    python benchmarks/prediction_speed.py [--threads 2] [--data data/cpu] [--json]

Batches of 32 runs with the default dataset's mix of lengths (about 2.3 real steps of 4 on
average, padded steps not run), random images unless --data is given. The profile splits one
training step into building the batch (from --data: decode, augment, pad), the forward pass,
the backward pass and the optimiser.
"""

from __future__ import annotations

import argparse
import json
import time

import numpy as np
import torch

from afford.prediction.config import PRESETS
from afford.prediction.model import PredictionNet
from afford.prediction.train import make_optimizer, sequence_loss
from afford.training.memory import keep_freed_memory

PAPER_BATCHES = 1_000_000
# Run lengths of a training batch: the default dataset's random starts give about this mix.
LENGTHS = (1, 1, 1, 1, 1, 1, 1, 1, 2, 2, 2, 2, 2, 2, 3, 3, 3, 3, 3, 3, 3, 4, 4, 4, 4, 4, 4, 4, 4, 4, 4, 4)


def random_batch(b: int) -> tuple[torch.Tensor, torch.Tensor, torch.Tensor]:
    g = torch.Generator().manual_seed(0)
    images = torch.rand(b, 5, 4, 128, 128, generator=g)
    actions = torch.rand(b, 4, 7, generator=g)
    actions[..., 0] = torch.randint(0, 3, (b, 4), generator=g).float()
    actions[..., 1] = actions[..., 1] * 0.4 - 0.2
    actions[..., 2] = 0.15 + actions[..., 2] * 0.3
    actions[..., 3] = actions[..., 3] * 0.1
    actions[..., 4] *= 360
    steps = torch.tensor([LENGTHS[k % len(LENGTHS)] for k in range(b)])
    return images, actions, steps


def profile(config, repeats: int, batch_source=None) -> dict:
    net = PredictionNet(config)
    opt = make_optimizer(net, config)
    batch = random_batch(config.training.batch_size)
    sequence_loss(net, *batch).backward()  # warm-up
    times = {"batch": 0.0, "forward": 0.0, "backward": 0.0, "optimizer": 0.0}
    t_all = time.perf_counter()
    for _ in range(repeats):
        t0 = time.perf_counter()
        if batch_source is not None:
            batch = next(batch_source)
        t1 = time.perf_counter()
        loss = sequence_loss(net, *batch)
        t2 = time.perf_counter()
        opt.zero_grad()
        loss.backward()
        t3 = time.perf_counter()
        opt.step()
        t4 = time.perf_counter()
        for k, dt in zip(times, (t1 - t0, t2 - t1, t3 - t2, t4 - t3), strict=True):
            times[k] += dt / repeats
    return {
        "parameters": sum(p.numel() for p in net.parameters()),
        "batches_per_second": round(repeats / (time.perf_counter() - t_all), 3),
        "seconds": {k: round(v, 4) for k, v in times.items()},
    }


def data_batches(data_dir: str, batch_size: int):
    from torch.utils.data import DataLoader

    from afford.data.augment import AugmentConfig
    from afford.data.format import Dataset
    from afford.data.torch_data import PredictionData, collate_prediction

    train = PredictionData(
        Dataset(data_dir), "train", 4, AugmentConfig(position_noise=0.002, angle_noise=1.0)
    )
    loader = DataLoader(
        train, batch_size=batch_size, shuffle=True, drop_last=True, collate_fn=collate_prediction
    )
    while True:
        yield from loader


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--data", help="build the cpu preset's batches from this dataset (in the loop)")
    ap.add_argument("--json", action="store_true")
    ap.add_argument("--no-keep-memory", action="store_true", help="leave glibc's malloc as it is (as before)")
    args = ap.parse_args()
    if not args.no_keep_memory:
        keep_freed_memory()  # as `afford train` does
    torch.set_num_threads(args.threads)
    np.random.seed(0)
    result = {"threads": args.threads, "keep_freed_memory": not args.no_keep_memory}
    cases = {
        "cpu": PRESETS["cpu"],
        "dense-cpu": PRESETS["dense-cpu"],
        "paper": PRESETS["paper"],
    }
    for name, config in cases.items():
        result[name] = profile(config, args.repeats)
    if args.data:
        result["cpu, batches from data"] = profile(
            PRESETS["cpu"], args.repeats, data_batches(args.data, PRESETS["cpu"].training.batch_size)
        )
    result["paper"]["projected_hours_for_1M_batches"] = round(
        PAPER_BATCHES / result["paper"]["batches_per_second"] / 3600, 1
    )
    if args.json:
        print(json.dumps(result, indent=2))
        return
    for name in result:
        if name in ("threads", "keep_freed_memory"):
            continue
        r = result[name]
        parts = ", ".join(f"{k} {v * 1000:.0f} ms" for k, v in r["seconds"].items() if v > 0.0005)
        print(
            f"{name:24s} {r['parameters']:>10,} params  {r['batches_per_second']:6.2f} batches/s  ({parts})"
        )
    print(
        f"paper preset, 1 M batches (the paper's schedule) on {args.threads} threads: "
        f"{result['paper']['projected_hours_for_1M_batches']:.0f} h"
    )


if __name__ == "__main__":
    from afford.errors import exit_on_user_error

    exit_on_user_error(main)
