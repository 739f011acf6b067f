"""`afford train dynamics` and `afford eval dynamics`: the object world model's P^a."""

from __future__ import annotations

import json
from pathlib import Path

from afford.cli.errors import CLIError


def cmd_train_dynamics(args) -> int:
    from afford.objects.dynamics import PRESETS
    from afford.objects.train import train
    from afford.training.overrides import apply_overrides, preset_config

    config = preset_config(PRESETS, args.preset, steps=args.steps, threads=args.threads)
    config = apply_overrides(config, args.set)
    if args.fraction is not None and not 0 < args.fraction <= 1:
        raise CLIError(f"--fraction must be in (0, 1], not {args.fraction}")
    try:
        state = train([args.data, *(args.more_data or [])], config, args.out, not args.json, args.fraction)
    except KeyboardInterrupt:
        print(f"interrupted; the last checkpoint is in {args.out}: run the same command again to continue")
        return 130
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
            f"best val loss {state.best:.4f}; curves: {record['curves']}"
        )
    return 0


def cmd_eval_dynamics(args) -> int:
    from afford.objects.measure import measure, table
    from afford.objects.train import load_dynamics
    from afford.objects.transitions import read_transitions

    net = load_dynamics(args.weights)
    split = None if args.split == "all" else args.split
    t = read_transitions(args.data, split, args.limit)
    if len(t) == 0:
        raise CLIError(f"{args.data}: no executions in the {args.split} split")
    if net.config.arm_path and t.paths.size and (t.paths != t.paths).any():
        raise CLIError(f"{args.data}: no arm paths recorded, and {args.weights} takes them as input")
    report = measure(net, t)
    report = {"weights": str(args.weights), "data": str(args.data), "split": args.split, **report}
    if args.out:
        Path(args.out).parent.mkdir(parents=True, exist_ok=True)
        Path(args.out).write_text(json.dumps(report, indent=2) + "\n")
    print(json.dumps(report, indent=2) if args.json else table(report))
    return 0


def add_train_parser(tsub) -> None:
    from afford.objects.dynamics import PRESETS

    p = tsub.add_parser(
        "dynamics",
        help="train the object dynamics (P^a over objects)",
        description="Train the object world model's dynamics: one interaction network per affordance "
        "type over the objects' true states, K outcomes with their probabilities (objects/dynamics.py). "
        "Learns from poses alone, so a dataset made with `afford generate --poses-only` serves. Progress "
        "bar; RUN/last.safetensors is written at every evaluation and a re-run of the same command "
        "resumes from it.",
    )
    p.add_argument("--data", required=True, metavar="DIR", help="a dataset (its val split validates)")
    p.add_argument(
        "--more-data", action="append", metavar="DIR", help="also train on this dataset's train split"
    )
    p.add_argument("--out", required=True, metavar="RUN", help="run folder (checkpoints, logs)")
    p.add_argument("--preset", choices=tuple(PRESETS), default="cpu")
    p.add_argument("--steps", type=int, help="override the preset's number of batches")
    p.add_argument("--threads", type=int, help="torch threads (default: the preset's)")
    p.add_argument(
        "--set",
        action="append",
        metavar="KEY=VALUE",
        help="change one field of the preset's config (repeatable), e.g. --set arm_path=true",
    )
    p.add_argument(
        "--fraction", type=float, metavar="F", help="train on this share of the executions (a learning curve)"
    )
    p.add_argument("--json", action="store_true", help="no progress bar; print a JSON report")
    p.set_defaults(func=cmd_train_dynamics)


def add_eval_parser(esub) -> None:
    p = esub.add_parser(
        "dynamics",
        help="where the object dynamics put objects, against copying",
        description="Predict every execution of a dataset from its true start state and measure, per "
        "group of objects (acted on, per type; each side-effect kind; all side-effect objects; still), "
        "the distance in the state image between predicted and true centres: median, 90th percentile, "
        "shares within 3 px and 0.5 px, the best of the K outcomes; beside copying the start. Also the "
        "off-the-table F1 and the calibration of the outcomes' probabilities.",
    )
    p.add_argument("--weights", required=True, metavar="FILE", help="a dynamics checkpoint or weights file")
    p.add_argument("--data", required=True, metavar="DIR")
    p.add_argument(
        "--split",
        choices=("train", "val", "test", "all"),
        default="test",
        help="default test; all: every sequence",
    )
    p.add_argument("--limit", type=int, metavar="N", help="the split's first N sequences")
    p.add_argument("--out", metavar="FILE.json", help="also write the report here")
    p.add_argument("--json", action="store_true")
    p.set_defaults(func=cmd_eval_dynamics)
