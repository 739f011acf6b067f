"""`afford train goals` and `afford eval goals`: the agreement model of goal sentences (paper V)."""

from __future__ import annotations

import json
from pathlib import Path

from afford.cli.errors import CLIError
from afford.words.config import PRESETS as AGREEMENT_PRESETS


def cmd_train_goals(args) -> int:
    from afford.training.overrides import apply_overrides, preset_config
    from afford.words.config import PRESETS
    from afford.words.train import train

    config = apply_overrides(
        preset_config(PRESETS, args.preset, steps=args.steps, threads=args.threads), args.set
    )
    try:
        state = train(
            args.data, config, args.out, progress=not args.json, predicted=args.predicted, init=args.init
        )
    except KeyboardInterrupt:
        print(f"interrupted; the last checkpoint is in {args.out}: run the same command again to continue")
        return 130
    record = {
        "run": str(args.out),
        "steps": state.step,
        "best_val_loss": state.best,
        "training_seconds": round(state.seconds, 1),
    }
    if args.json:
        print(json.dumps(record, indent=2))
    else:
        print(
            f"{args.out}: {state.step} steps in {state.seconds / 60:.1f} min, best val loss {state.best:.4f}"
        )
    return 0


def cmd_eval_goals(args) -> int:
    import torch

    from afford.shipped import agreement_net
    from afford.words.evaluate import evaluate, format_table

    if args.run is None:
        from afford.shipped import AGREEMENT_FILE, WEIGHTS

        checkpoint, folder = WEIGHTS / AGREEMENT_FILE, Path(args.out)
    else:
        checkpoint, folder = Path(args.run) / args.checkpoint, Path(args.run)
        if not checkpoint.is_file():
            raise CLIError(f"{checkpoint}: no such checkpoint")
    net = agreement_net(checkpoint)
    torch.set_num_threads(net.config.threads)
    result = evaluate(net, args.data, args.predicted, progress=not args.json)
    folder.mkdir(parents=True, exist_ok=True)
    (folder / "goals.json").write_text(json.dumps(result, indent=2) + "\n")
    print(json.dumps(result, indent=2) if args.json else format_table(result))
    return 0


def add_train_parser(tsub) -> None:
    p = tsub.add_parser(
        "goals",
        help="train the agreement model of goal sentences",
        description="Train the model that scores how well a sentence describes a state (paper V's "
        "proposal in place of eq. (5)): clauses about each state's true poses, half of them false, "
        "sampled afresh at every draw (words/sentences.py). Progress bar; RUN/last.safetensors is "
        "written at every evaluation and a re-run of the same command resumes from it.",
    )
    p.add_argument("--data", required=True, metavar="DIR", help="a dataset made by `afford generate`")
    p.add_argument("--out", required=True, metavar="RUN", help="run folder (checkpoints, logs)")
    p.add_argument("--preset", choices=tuple(AGREEMENT_PRESETS), default="cpu")
    p.add_argument(
        "--predicted",
        metavar="FILE.npz",
        help="also train on these predicted states (`afford data predict`), each judged by the true "
        "state it predicts: predicted_fraction of the draws (--set to change)",
    )
    p.add_argument("--steps", type=int, help="override the preset's number of batches")
    p.add_argument("--threads", type=int, help="torch threads (default: the preset's)")
    p.add_argument(
        "--set", action="append", metavar="KEY=VALUE", help="change one field of the preset's config"
    )
    p.add_argument("--init", metavar="CHECKPOINT", help="start a new run from these weights")
    p.add_argument("--json", action="store_true", help="no progress bar; print a JSON report")
    p.set_defaults(func=cmd_train_goals)


def add_eval_parser(esub) -> None:
    p = esub.add_parser(
        "goals",
        help="the agreement model's ROC AUC per relation",
        description="ROC AUC per relation of the agreement model: clauses drawn about every test state "
        "(half true), scored on the true image and, with --predicted, on the prediction net's images "
        "of the same states one to three steps deep (a file of `afford data predict --split test`).",
    )
    p.add_argument(
        "--run", metavar="RUN", help="a training run (default: the weights shipped in the package)"
    )
    p.add_argument("--out", default="out/eval-goals", metavar="DIR", help="where results go without --run")
    p.add_argument("--data", required=True, metavar="DIR")
    p.add_argument("--predicted", metavar="FILE.npz", help="predicted states of the test split")
    p.add_argument("--checkpoint", default="best.safetensors", help="file in RUN (default best.safetensors)")
    p.add_argument("--json", action="store_true")
    p.set_defaults(func=cmd_eval_goals)


def goal_reading(sentence: str, statement, state) -> dict:
    """How `afford plan --goal` read its sentence, shown before it plans so that a misreading
    is caught before the robot acts on it: each clause in words (as the agreement model is
    given it, the objects by name) and as a fact ('[not] relation subject [other]')."""
    from afford.words.sentences import written

    facts = [_fact(c, state) for c in statement.clauses]
    clauses = [written((c,), state) or f for c, f in zip(statement.clauses, facts, strict=True)]
    return {"sentence": sentence, "clauses": clauses, "facts": facts}


def reading_line(reading: dict) -> str:
    return f"goal read as: {'; '.join(reading['clauses'])}"


def _fact(clause, state) -> str:
    f = clause.fact
    other = state.slots[f.other] if isinstance(f.other, int) else f.other
    said = ("not" if clause.negated else "", f.relation, state.slots[f.subject], other)
    return " ".join(w for w in said if w)
