"""`afford train recognition|prediction`, `afford eval recognition|prediction|futures`."""

from __future__ import annotations

import json
from pathlib import Path

from afford.cli import objects, words
from afford.cli.errors import CLIError
from afford.cli.options import add_weights_argument
from afford.shipped import Nets
from afford.training.checkpoint import BEST


def cmd_train(args) -> int:
    """Train the net named by `args.net` with its preset and overrides."""
    from afford.training.distributed import DistributedError, is_main_process, leave_world
    from afford.training.overrides import apply_overrides, preset_config

    if args.net == "recognition":
        from afford.recognition.config import PRESETS
        from afford.recognition.train import train

        config = preset_config(PRESETS, args.preset, steps=args.steps, threads=args.threads)
    else:
        from afford.prediction.config import PRESETS
        from afford.prediction.train import train

        pixel = not args.no_affordance_pixel
        steps, threads = args.steps, args.threads
        config = preset_config(PRESETS, args.preset, steps=steps, threads=threads, pixel_input=pixel)
    config = apply_overrides(config, args.set)  # a bad --set is a UserError: one line
    try:
        extra = (
            {"predicted": args.predicted}
            if args.net == "recognition"
            else {"more_data": tuple(args.more_data or ())}
        )
        state = train(
            args.data, config, args.out, progress=not args.json, init=args.init, device=args.device, **extra
        )
    except DistributedError as e:
        raise CLIError(str(e)) from None
    except KeyboardInterrupt:
        if is_main_process():
            out = args.out
            print(f"interrupted; the last checkpoint is in {out}: run the same command again to continue")
        return 130
    finally:
        leave_world()
    if not is_main_process():
        return 0
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
            f"best val loss {state.best:.5f}; curves: {record['curves']}"
        )
    return 0


# The paper's table each evaluation reproduces, and the folder its pictures go to.
EVALS = {"recognition": ("table1.json", "detections"), "prediction": ("table2.json", "predictions")}


def cmd_eval(args) -> int:
    """Evaluate a trained net: its paper table and pictures.

    Without --run, the weights shipped in the package are evaluated, writing to --out.
    """
    if args.net == "futures":
        return cmd_futures(args)
    if args.net == "recognition":
        from afford.recognition.evaluate import evaluate, evaluate_shipped, format_table

        if args.run is None:
            folder = Path(args.out)
            result = evaluate_shipped(Nets().recognizer, args.data, folder)
        else:
            _check_run(args.run)
            result, folder = evaluate(args.run, args.data, checkpoint=args.checkpoint), Path(args.run)
    elif args.objects is not None:
        from afford.objects.rollout import ObjectRollout
        from afford.prediction.evaluate import evaluate_world, format_table

        nets = Nets(None if args.objects == "shipped" else args.objects)
        world = ObjectRollout(nets.perception, nets.dynamics)
        folder = Path(args.out)
        recognizer = None if args.no_futures else Nets(args.recognition).recognizer
        result = evaluate_world(
            world, f"objects ({nets.folder})", args.data, folder / EVALS[args.net][1], recognizer
        )
    else:
        from afford.prediction.evaluate import evaluate, format_table

        if args.run is None:
            from afford.shipped import PREDICTION_FILE, WEIGHTS

            checkpoint, folder = WEIGHTS / PREDICTION_FILE, Path(args.out)
        else:
            _check_run(args.run)
            checkpoint, folder = Path(args.run) / args.checkpoint, Path(args.run)
        folder.mkdir(parents=True, exist_ok=True)
        recognizer = None
        if not args.no_futures:
            recognizer = Nets(args.recognition).recognizer
        result = evaluate(checkpoint, args.data, pictures=folder / EVALS[args.net][1], recognizer=recognizer)
        if "choice_head" in result:  # the head's calibration, for export
            from afford.prediction.calibration import CALIBRATION_FILE, format_calibration

            record = result["choice_head"]
            (folder / CALIBRATION_FILE).write_text(json.dumps(record, indent=2) + "\n")
            if not args.json:
                print(format_calibration(record))
    _report(args, result, folder, *EVALS[args.net], format_table(result))
    return 0


def _report(args, result: dict, folder: Path, record: str, pictures: str, text: str) -> None:
    """Write RECORD in the folder; print JSON or the table and where the pictures are."""
    folder.mkdir(parents=True, exist_ok=True)
    (folder / record).write_text(json.dumps(result, indent=2) + "\n")
    if args.json:
        print(json.dumps(result, indent=2))
    else:
        print(text)
        print(f"pictures: {folder / pictures}/; record: {folder / record}")


def cmd_futures(args) -> int:
    """Recognition on predicted futures, beside the true states and copying the start."""
    import torch

    from afford.data.format import Dataset
    from afford.prediction.futures import BASELINES, format_report, future_recalls, net_predictor, pictures

    nets = Nets(args.weights)
    recognizer, net = nets.recognizer, nets.predictor
    torch.set_num_threads(net.config.training.threads)
    data = Dataset(args.data)
    folder = Path(args.out)
    predict = net_predictor(net)
    recalls = future_recalls(
        {"net": predict, "copy": BASELINES["copy"]}, recognizer, data, "test", args.limit
    )
    result = {"weights": args.weights or "shipped", "threshold": recognizer.threshold, **recalls}
    result["pictures"] = pictures(predict, recognizer, data, folder / "futures")
    _report(args, result, folder, "futures.json", "futures", format_report(result))
    return 0


def _check_run(run: str) -> None:

    if not Path(run).is_dir():
        raise CLIError(f"{run}: no such run folder (make one with `afford train ...`)")


def _preset_names() -> dict[str, tuple[str, ...]]:
    from afford.prediction.config import PRESETS as PREDICTION
    from afford.recognition.config import PRESETS as RECOGNITION

    return {"recognition": tuple(RECOGNITION), "prediction": tuple(PREDICTION)}


PRESET_NAMES = _preset_names()


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
        p.add_argument("--preset", choices=PRESET_NAMES[net], default="cpu")
        p.add_argument("--out", required=True, metavar="RUN", help="run folder (checkpoints, logs)")
        p.add_argument("--steps", type=int, help="override the preset's number of batches")
        p.add_argument("--threads", type=int, help="torch threads (default: the preset's)")
        p.add_argument(
            "--set",
            action="append",
            metavar="KEY=VALUE",
            help="change one field of the preset's config (repeatable), e.g. --set lr=3e-4, or by "
            "its path in a grouped config, --set training.lr=3e-4; a tuple as a comma list",
        )
        p.add_argument(
            "--init",
            metavar="CHECKPOINT",
            help="start a new run from these weights (fine-tuning; same architecture)",
        )
        p.add_argument(
            "--device",
            choices=("auto", "cpu", "cuda"),
            default="auto",
            help="where to train: a GPU when torch sees one (auto, the default), or the CPU; under "
            "torchrun each rank takes the GPU of its local rank",
        )
        p.add_argument("--json", action="store_true", help="no progress bar; print a JSON report")
        if net == "recognition":
            p.add_argument(
                "--predicted",
                metavar="FILE.npz",
                help="also train on these predicted states (`afford data predict`), labelled by the "
                "true states' affordances: predicted_fraction of the batches (--set to change)",
            )
        if net == "prediction":
            p.add_argument(
                "--no-affordance-pixel",
                action="store_true",
                help="leave the affordance pixel's RGBD out of the action vector (Table 2 ablation)",
            )
            p.add_argument(
                "--more-data",
                action="append",
                metavar="DIR",
                help="also train on this dataset's train split (repeatable), e.g. one made with "
                "`afford generate --actions effects`; validation stays on --data's",
            )
        p.set_defaults(func=cmd_train)
    words.add_train_parser(tsub)
    objects.add_train_parser(tsub)

    e = sub.add_parser("eval", help="evaluate a trained net", description="Evaluate a trained net.")
    esub = e.add_subparsers(dest="net", required=True)
    r = esub.add_parser(
        "recognition",
        help="the paper's Table 1",
        description="With --run: tune the confidence cut-off on val (saved in RUN/threshold.json); "
        "without: the shipped weights with their shipped cut-off. Then report the "
        "paper's Table 1 on test and on 100 training examples: recall per type (right type, within 2.5 cm "
        "and 5 degrees; any angle for a symmetric affordance) and spurious detections per image. Writes "
        "Fig. 6-style pictures to RUN/detections/.",
    )
    p = esub.add_parser(
        "prediction",
        help="the paper's Table 2",
        description="The paper's Table 2: mean absolute RGBD error per step (1-4) over all pixels and "
        "over the pixels that changed (by more than 0.02, and at all), mean (sd), on test and 500 training "
        "sequences, beside copying the input. Writes Fig. 7-style pictures of canonical and non-canonical "
        "effects to RUN/predictions/. For a net with a side-effect outcome, also its choice head: how "
        "often it expects a side effect against how often one follows, and Platt scaling fitted on val "
        "(RUN/calibration.json, which `afford weights export` puts in the exported net's config).",
    )
    for q, name in ((r, "recognition"), (p, "prediction")):
        q.add_argument(
            "--run", metavar="RUN", help="a training run (default: the weights shipped in the package)"
        )
        q.add_argument(
            "--out", default=f"out/eval-{name}", metavar="DIR", help="where results go without --run"
        )
    p.add_argument(
        "--recognition",
        metavar="DIR",
        help="weights folder whose recognition net runs on the predicted states (default: the shipped one)",
    )
    p.add_argument("--no-futures", action="store_true", help="skip recognition on the predicted states")
    p.add_argument(
        "--objects",
        nargs="?",
        const="shipped",
        metavar="DIR",
        help="evaluate the object world model (the perception and dynamics nets of the weights folder DIR, "
        "objects/perception.safetensors and objects/dynamics.safetensors; without DIR the shipped ones) "
        "instead of a prediction net, on the same measures",
    )
    f = esub.add_parser(
        "futures",
        help="recognition on predicted states",
        description="Future-affordance recall, a measure the paper lacks: each test sequence is rolled out "
        "by the prediction net from its first image through its executed actions, the recognition net runs "
        "on every predicted state, and its detections are scored against the true state's affordances by "
        "Table 1's criteria (recall, spurious per image), per step 1-4, beside the same net on the true "
        "states and on the start image copied forward. Writes Fig. 6-style pictures of detections on "
        "predicted states to OUT/futures/.",
    )
    f.add_argument("--data", required=True, metavar="DIR")
    add_weights_argument(f, detail=True)
    f.add_argument(
        "--limit", type=int, metavar="N", help="evaluate N test sequences, evenly spread (default all)"
    )
    f.add_argument("--out", default="out/eval-futures", metavar="DIR")
    f.add_argument("--json", action="store_true")
    f.set_defaults(func=cmd_eval)
    for q in (r, p):
        q.add_argument("--data", required=True, metavar="DIR")
        q.add_argument("--checkpoint", default=BEST, help=f"file in RUN (default {BEST})")
        q.add_argument("--json", action="store_true")
        q.set_defaults(func=cmd_eval)
    words.add_eval_parser(esub)
    objects.add_eval_parser(esub)
