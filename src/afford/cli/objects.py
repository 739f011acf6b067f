"""`afford train dynamics` and `afford eval dynamics`: the object world model's P^a."""

from __future__ import annotations

import json
from pathlib import Path

from afford.cli.errors import CLIError


def cmd_train_dynamics(args) -> int:
    from afford.objects.calibration import CALIBRATION_FILE
    from afford.objects.dynamics import PRESETS
    from afford.objects.train import train
    from afford.training.overrides import apply_overrides, preset_config

    config = preset_config(PRESETS, args.preset, steps=args.steps, threads=args.threads)
    config = apply_overrides(config, args.set)
    if args.fraction is not None and not 0 < args.fraction <= 1:
        raise CLIError(f"--fraction must be in (0, 1], not {args.fraction}")
    try:
        state = train(
            [args.data, *(args.more_data or [])],
            config,
            args.out,
            not args.json,
            args.fraction,
            init=args.init,
        )
    except KeyboardInterrupt:
        print(f"interrupted; the last checkpoint is in {args.out}: run the same command again to continue")
        return 130
    record = {
        "run": str(args.out),
        "steps": state.step,
        "best_val_loss": state.best,
        "training_seconds": round(state.seconds, 1),
        "curves": str(Path(args.out) / "curves.png"),
        "calibration": json.loads((Path(args.out) / CALIBRATION_FILE).read_text()),
    }
    if args.json:
        print(json.dumps(record, indent=2))
    else:
        print(
            f"{args.out}: {state.step} steps in {state.seconds / 60:.1f} min, "
            f"best val loss {state.best:.4f}; curves: {record['curves']}"
        )
        fit = record["calibration"]
        if fit["executions"]:
            print(
                f"outcome temperature {fit['outcome_temperature']:g}, fitted on {fit['executions']} val "
                f"executions (log-loss {fit['nll_raw']:.3f} -> {fit['nll_calibrated']:.3f})"
            )
        else:
            print("outcome temperature 1: no val execution whose outcomes differ")
    return 0


def cmd_eval_dynamics(args) -> int:
    from afford.objects.measure import measure, simulator_predictor, table
    from afford.objects.train import load_dynamics
    from afford.objects.transitions import read_transitions

    if (args.weights is not None) == args.simulator:
        raise CLIError("give one of --weights FILE (a dynamics net) and --simulator")
    split = None if args.split == "all" else args.split
    t = read_transitions(args.data, split, args.limit)
    if len(t) == 0:
        raise CLIError(f"{args.data}: no executions in the {args.split} split")
    if args.simulator:
        predictor = simulator_predictor()
    else:
        predictor = load_dynamics(args.weights).outcomes
    before, seen_by = None, "true"
    if args.perception:
        before, seen_by = perceived_starts(args.perception, args.data, t), str(args.perception)
    report = measure(predictor, t, before)
    if args.pictures:
        report["pictures"] = dynamics_pictures(predictor, t, before, args.pictures)
    report = {
        "model": "simulator" if args.simulator else str(args.weights),
        "data": str(args.data),
        "split": args.split,
        "start": seen_by,
        **report,
    }
    if args.out:
        Path(args.out).parent.mkdir(parents=True, exist_ok=True)
        Path(args.out).write_text(json.dumps(report, indent=2) + "\n")
    print(json.dumps(report, indent=2) if args.json else table(report))
    return 0


def dynamics_pictures(predictor, t, before, out: str, count: int = 8) -> str:
    """Executions with side effects, each drawn from its true start: where objects were
    (white), went (green) and were predicted (red)."""
    import numpy as np

    from afford.objects.draw import Drawer
    from afford.objects.picture import grid, moved

    rows = [i for i, step in enumerate(t.effects()) if not step.canonical]
    rows = [rows[int(j)] for j in np.linspace(0, len(rows) - 1, min(count, len(rows)))] if rows else []
    if not rows:
        return "none: no execution with a side effect"
    start = t.before if before is None else before
    sub = t.subset(np.array(rows))
    poses, _ = predictor(start[rows], sub.held_before, sub.actions).likeliest()
    drawer = Drawer()
    pictures = [
        moved(drawer.render(sub.before[i], int(sub.held_before[i])), sub.before[i], sub.after[i], poses[i])
        for i in range(len(rows))
    ]
    Path(out).parent.mkdir(parents=True, exist_ok=True)
    grid(pictures, 4).save(out)
    return out


def perceived_starts(perception: str, data_dir: str, t):
    """Each execution's start state as the perception net sees it (`perception_measure`); the
    held slots it sees replace `t`'s."""
    from afford.data.format import DataError, Dataset
    from afford.objects.perception_measure import perceived_starts as seen_starts
    from afford.objects.perception_train import load_perception

    try:
        before, t.held_before = seen_starts(load_perception(perception), Dataset(data_dir), t)
    except DataError as e:
        raise CLIError(str(e)) from None
    return before


def cmd_train_perception(args) -> int:
    from afford.objects.perception import PRESETS
    from afford.objects.perception_train import train
    from afford.training.overrides import apply_overrides, preset_config

    config = apply_overrides(
        preset_config(PRESETS, args.preset, steps=args.steps, threads=args.threads), args.set
    )
    try:
        state = train(args.data, config, args.out, not args.json, init=args.init)
    except KeyboardInterrupt:
        print(f"interrupted; the last checkpoint is in {args.out}: run the same command again to continue")
        return 130
    record = {
        "run": str(args.out),
        "steps": state.step,
        "best_val_loss": state.best,
        "training_seconds": round(state.seconds, 1),
    }
    print(
        json.dumps(record, indent=2)
        if args.json
        else f"{args.out}: {state.step} steps in {state.seconds / 60:.1f} min, best val loss {state.best:.4f}"
    )
    return 0


def cmd_eval_objects(args) -> int:
    from afford.data.format import Dataset
    from afford.objects.perception_measure import measure_perception, perception_table
    from afford.objects.perception_train import load_perception

    net = load_perception(args.weights)
    split = None if args.split == "all" else args.split
    data = Dataset(args.data)
    report = {
        "weights": str(args.weights),
        "data": str(args.data),
        "split": args.split,
        **measure_perception(net, data, split, args.limit),
    }
    if args.pictures:
        report["pictures"] = perception_pictures(net, data, split, args.pictures)
    if args.out:
        Path(args.out).parent.mkdir(parents=True, exist_ok=True)
        Path(args.out).write_text(json.dumps(report, indent=2) + "\n")
    print(json.dumps(report, indent=2) if args.json else perception_table(report))
    return 0


def perception_pictures(net, data, split: str | None, out: str, count: int = 8) -> str:
    """What perception sees in `count` images of the split, evenly spread."""
    import numpy as np

    from afford.objects.perceive import perceive
    from afford.objects.perception_train import states_of
    from afford.objects.picture import grid, perceived

    items = states_of(data, split)
    items = [items[int(j)] for j in np.linspace(0, len(items) - 1, min(count, len(items)))]
    images = np.stack([data.sequence(i).image(k) for i, k in items])
    Path(out).parent.mkdir(parents=True, exist_ok=True)
    grid([perceived(im, objs) for im, objs in zip(images, perceive(net, images), strict=True)], 4).save(out)
    return out


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
    p.add_argument(
        "--init", metavar="FILE", help="a new run starts from these dynamics weights (fine-tuning)"
    )
    p.add_argument("--out", required=True, metavar="RUN", help="run folder (checkpoints, logs)")
    p.add_argument("--preset", choices=tuple(PRESETS), default="cpu")
    p.add_argument("--steps", type=int, help="override the preset's number of batches")
    p.add_argument("--threads", type=int, help="torch threads (default: the preset's)")
    p.add_argument(
        "--set",
        action="append",
        metavar="KEY=VALUE",
        help="change one field of the preset's config (repeatable), e.g. --set rounds=3",
    )
    p.add_argument(
        "--fraction", type=float, metavar="F", help="train on this share of the executions (a learning curve)"
    )
    p.add_argument("--json", action="store_true", help="no progress bar; print a JSON report")
    p.set_defaults(func=cmd_train_dynamics)

    from afford.objects.perception import PRESETS as SEEING

    q = tsub.add_parser(
        "perception",
        help="train the object perception net (E over objects)",
        description="Train the net that sees the objects in a state image: per pixel the kind seen, "
        "centre maps, offsets to the centre, height, axes and held (objects/perception.py), on a "
        "dataset made with `afford generate --masks`. Resumable like every training run.",
    )
    q.add_argument("--data", required=True, metavar="DIR", help="a dataset with instance masks")
    q.add_argument("--out", required=True, metavar="RUN")
    q.add_argument(
        "--init", metavar="FILE", help="a new run starts from these perception weights (training on)"
    )
    q.add_argument("--preset", choices=tuple(SEEING), default="cpu")
    q.add_argument("--steps", type=int, help="override the preset's number of batches")
    q.add_argument("--threads", type=int, help="torch threads (default: the preset's)")
    q.add_argument(
        "--set", action="append", metavar="KEY=VALUE", help="change one field of the preset's config"
    )
    q.add_argument("--json", action="store_true", help="no progress bar; print a JSON report")
    q.set_defaults(func=cmd_train_perception)


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
    p.add_argument("--weights", metavar="FILE", help="a dynamics checkpoint or weights file")
    p.add_argument(
        "--simulator",
        action="store_true",
        help="measure the simulator run from the start states instead of a net: with --perception, "
        "the perceived-state simulator, which tells what perception costs",
    )
    p.add_argument("--data", required=True, metavar="DIR")
    p.add_argument(
        "--split",
        choices=("train", "val", "test", "all"),
        default="test",
        help="default test; all: every sequence",
    )
    p.add_argument("--limit", type=int, metavar="N", help="the split's first N sequences")
    p.add_argument("--out", metavar="FILE.json", help="also write the report here")
    p.add_argument(
        "--perception",
        metavar="FILE",
        help="start from the states this perception net sees in the start images (the dataset needs "
        "images and masks) instead of the true states",
    )
    p.add_argument("--pictures", metavar="FILE.png", help="draw 8 executions with side effects here")
    p.add_argument("--json", action="store_true")
    p.set_defaults(func=cmd_eval_dynamics)

    q = esub.add_parser(
        "objects",
        help="how well perception sees the objects",
        description="Run the perception net on every state image of a split (a dataset made with "
        "`afford generate --masks`) and report: the share of visible objects (20 pixels or more) found, "
        "spurious objects per image, kind right, centre error in the image (median, 95th percentile) "
        "and in 3D, upright / tipped / lying right, the block's tilt, mask IoU, the held object right, "
        "and images per second.",
    )
    q.add_argument("--weights", required=True, metavar="FILE", help="a perception checkpoint or weights file")
    q.add_argument("--data", required=True, metavar="DIR")
    q.add_argument("--split", choices=("train", "val", "test", "all"), default="test")
    q.add_argument("--limit", type=int, metavar="N", help="at most N images, evenly spread")
    q.add_argument("--out", metavar="FILE.json", help="also write the report here")
    q.add_argument("--pictures", metavar="FILE.png", help="draw what perception sees in 8 images here")
    q.add_argument("--json", action="store_true")
    q.set_defaults(func=cmd_eval_objects)
