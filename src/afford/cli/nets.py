"""`afford train recognition|prediction` and `afford eval recognition|prediction`."""

from __future__ import annotations

import json
from pathlib import Path


def cmd_train_recognition(args) -> int:
    from afford.recognition.train import config_for, train

    config = config_for(args.preset, steps=args.steps, threads=args.threads)
    try:
        state = train(args.data, config, args.out, progress=not args.json)
    except KeyboardInterrupt:
        print(f"interrupted; the last checkpoint is in {args.out}: run the same command again to continue")
        return 130
    return _report_training(args, state)


def cmd_train_prediction(args) -> int:
    from afford.prediction.train import config_for, train

    config = config_for(
        args.preset, steps=args.steps, threads=args.threads, pixel_input=not args.no_affordance_pixel
    )
    try:
        state = train(args.data, config, args.out, progress=not args.json)
    except KeyboardInterrupt:
        print(f"interrupted; the last checkpoint is in {args.out}: run the same command again to continue")
        return 130
    return _report_training(args, state)


def _report_training(args, state) -> int:
    record = {
        "run": str(args.out),
        "steps": state.step,
        "best_val_loss": state.best,
        "training_seconds": round(state.seconds, 1),
        "curves": str(Path(args.out) / "curves.png"),
    }
    if args.json:
        print(json.dumps(record, indent=2))
    else:
        print(
            f"{args.out}: {state.step} steps in {state.seconds / 60:.1f} min, "
            f"best val loss {state.best:.5f}; "
            f"curves: {record['curves']}"
        )
    return 0


def add_parsers(sub) -> None:
    t = sub.add_parser("train", help="train a net", description="Train the recognition or prediction net.")
    tsub = t.add_subparsers(dest="net", required=True)
    common = {
        "recognition": "Train the affordance recognition net (paper II.B) on a generated dataset.",
        "prediction": "Train the EM*D prediction pathway (paper II.C) on runs of 1-4 executions.",
    }
    for net, text in common.items():
        p = tsub.add_parser(
            net,
            help=text.split(" (")[0].lower(),
            description=text
            + " Progress bar; RUN/last.safetensors is written at every evaluation and a re-run "
            "of the same command resumes from it; TensorBoard events in RUN/tensorboard, "
            "curves in RUN/curves.png.",
        )
        p.add_argument("--data", required=True, metavar="DIR", help="a dataset made by `afford generate`")
        p.add_argument("--preset", choices=("cpu", "paper", "tiny"), default="cpu")
        p.add_argument("--out", required=True, metavar="RUN", help="run folder (checkpoints, logs)")
        p.add_argument("--steps", type=int, help="override the preset's number of batches")
        p.add_argument("--threads", type=int, help="torch threads (default: the preset's)")
        p.add_argument("--json", action="store_true", help="no progress bar; print a JSON report")
        if net == "prediction":
            p.add_argument(
                "--no-affordance-pixel",
                action="store_true",
                help="leave the affordance pixel's RGBD out of the action vector (Table 2 ablation)",
            )
        p.set_defaults(func=cmd_train_recognition if net == "recognition" else cmd_train_prediction)
