"""Recognition inference speed: images/s at batch 256 (the planner's batch), as trained, with
the batch norms folded (what `Recognizer` runs), and folded under bfloat16 autocast; and
training speed.

    python benchmarks/recognition_speed.py [--preset cpu] [--threads 2] [--json]

Random weights and random images: speed does not depend on either.
"""

from __future__ import annotations

import argparse
import json
import time

import torch

from afford.recognition.config import PRESETS
from afford.recognition.model import RecognitionNet, fused_for_inference


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--preset", default="cpu", choices=sorted(PRESETS))
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--json", action="store_true")
    args = ap.parse_args()
    torch.set_num_threads(args.threads)
    config = PRESETS[args.preset]
    net = RecognitionNet(config).eval()
    images = torch.rand(256, 4, 128, 128)

    def speed(model, bf16: bool = False) -> float:
        with torch.no_grad(), torch.autocast("cpu", dtype=torch.bfloat16, enabled=bf16):
            model(images[:8])  # warm-up
            t = time.perf_counter()
            for _ in range(args.repeats):
                model(images)
            return 256 * args.repeats / (time.perf_counter() - t)

    fused = fused_for_inference(net)
    inference = {"plain": speed(net), "folded": speed(fused), "folded_bf16": speed(fused, bf16=True)}
    infer = inference["folded"]
    net.train()
    opt = torch.optim.AdamW(net.parameters())
    batch = images[: config.batch_size]
    t = time.perf_counter()
    for _ in range(args.repeats):
        loss = net(batch).float().square().mean()
        opt.zero_grad()
        loss.backward()
        opt.step()
    train = args.repeats / (time.perf_counter() - t)
    result = {
        "preset": args.preset,
        "threads": args.threads,
        "parameters": sum(p.numel() for p in net.parameters()),
        "inference_images_per_second_batch_256": round(infer, 1),
        "inference_by_variant": {k: round(v, 1) for k, v in inference.items()},
        "training_batches_per_second": round(train, 3),
        "batch_size": config.batch_size,
    }
    if args.json:
        print(json.dumps(result, indent=2))
    else:
        print(
            f"recognition ({args.preset}, {result['parameters']:,} parameters, {args.threads} threads): "
            f"{infer:.0f} images/s at batch 256 (as trained {inference['plain']:.0f}, folded under bf16 "
            f"{inference['folded_bf16']:.0f}); training {train:.2f} batches/s at batch {config.batch_size}"
        )


if __name__ == "__main__":
    from afford.errors import exit_on_user_error

    exit_on_user_error(main)
