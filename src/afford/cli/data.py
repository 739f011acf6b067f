"""`afford generate` and `afford data info|show|verify|predict`."""

from __future__ import annotations

import json
from collections import Counter
from pathlib import Path

import numpy as np

from afford.cli.errors import CLIError
from afford.sim.affordance import Col
from afford.sim.affordances import TYPES
from afford.sim.layout import LAYOUTS


def cmd_generate(args) -> int:
    from afford.data.generate import GenerateConfig, generate

    config = GenerateConfig(
        sequences=args.sequences,
        seed=args.seed,
        workers=args.workers,
        shard_size=args.shard_size,
        turn_angles=args.turn_angles,
        actions_drawn=args.actions,
        layout=args.layout,
        images=not args.poses_only,
        masks=args.masks,
        splits_of=args.splits_of,
        executor="ray" if args.ray is not None else "local",
        address=args.ray or None,
    )
    try:
        report = generate(Path(args.out).resolve(), config, progress=not args.json)
    except KeyboardInterrupt:
        print(f"interrupted; finished shards are kept: run the same command again to continue ({args.out})")
        return 130
    record = {
        "out": str(args.out),
        "sequences": report.sequences,
        "shards_made": report.made_shards,
        "shards_already_there": report.skipped_shards,
        "shards_remade": report.remade,
        "executor": config.executor,
        "executions_made": report.executions,
        "failed_executions_redrawn": report.failed_executions,
        "seconds": round(report.seconds, 2),
        "executions_per_second": round(report.executions_per_second, 2),
    }
    if args.json:
        print(json.dumps(record, indent=2))
    else:
        for problem in report.remade:
            print(f"made again: {problem}")
        print(
            f"{args.out}: {report.sequences} sequences ({report.made_shards} shards made, "
            f"{report.skipped_shards} already there); {report.executions} executions in "
            f"{report.seconds:.0f} s = {report.executions_per_second:.1f}/s"
        )
    return 0


def dataset_info(root: Path) -> dict:
    from tqdm import tqdm

    from afford.data.effects import KINDS, summary_effects
    from afford.data.format import DataError, read_manifest, shard_path, shard_status, shard_summary
    from afford.data.visibility import Visibility

    m = read_manifest(root)
    present, missing = shard_status(root, m)
    lengths: Counter[int] = Counter()
    executed: Counter[str] = Counter()
    listed: Counter[str] = Counter()
    per_state: list[int] = []
    side: Counter[str] = Counter()  # executions with a side effect, per type
    kinds: Counter[str] = Counter()  # executions showing each kind of side effect
    bad: list[str] = []
    seen = Visibility() if m.generator.get("masks", False) else None
    for k in tqdm(present, desc="info", unit="shard", leave=False, disable=len(present) < 20):
        try:
            s = shard_summary(shard_path(root, k))
        except DataError as e:  # the rest of the dataset is still worth describing
            bad.append(str(e))
            continue
        lengths.update((s["state_count"] - 1).tolist())
        executed.update(TYPES[int(t)] for t in s["actions"][:, Col.TYPE])
        listed.update(TYPES[int(t)] for t in s["affordances"][:, Col.TYPE])
        per_state.extend(s["aff_count"].tolist())
        for steps in summary_effects(s, tuple(m.slots)):
            side.update(step.type for step in steps if not step.canonical)
            for step in steps:
                kinds.update(step.kinds)
        if seen is not None:
            with np.load(shard_path(root, k), allow_pickle=False) as z:
                seen.add(z["masks"], s["poses"], s["held"], tuple(m.slots))
    disk = sum(f.stat().st_size for f in root.rglob("*") if f.is_file())
    counts = np.array(per_state) if per_state else np.zeros(1)
    return {
        "path": str(root),
        "format_version": m.version,
        "sequences_planned": m.sequences,
        "sequences_present": int(sum(lengths.values())),
        "shards": {"present": len(present) - len(bad), "missing": len(missing), "corrupt": bad},
        "seed": m.seed,
        "splits": {name: stop - start for name, (start, stop) in m.splits.items()},
        "executions": int(sum(executed.values())),
        "executions_per_type": {t: executed.get(t, 0) for t in TYPES},
        "sequence_length_histogram": {str(n): lengths.get(n, 0) for n in range(m.max_steps + 1)},
        "affordances_per_state": {
            "mean": round(float(counts.mean()), 2),
            "min": int(counts.min()),
            "max": int(counts.max()),
            "per_type": {t: round(listed.get(t, 0) / max(len(per_state), 1), 2) for t in TYPES},
        },
        "side_effects": {
            "executions": int(sum(side.values())),
            "per_type": {t: side.get(t, 0) for t in TYPES},
            "per_kind": {k: kinds.get(k, 0) for k in KINDS},
        },
        "visibility": None if seen is None else seen.as_dict(),
        "disk_bytes": disk,
    }


def cmd_data_info(args) -> int:
    info = dataset_info(Path(args.dir))
    if args.json:
        print(json.dumps(info, indent=2))
        return 0
    print(f"{info['path']}  (format version {info['format_version']}, seed {info['seed']})")
    print(
        f"  sequences   {info['sequences_present']} of {info['sequences_planned']}"
        f"  (shards: {info['shards']['present']} good, {info['shards']['missing']} missing, "
        f"{len(info['shards']['corrupt'])} corrupt)"
    )
    for problem in info["shards"]["corrupt"]:
        print(f"  {problem}: re-run the same `afford generate` to make it again")
    print("  splits      " + ", ".join(f"{k} {v}" for k, v in info["splits"].items()))
    per = ", ".join(f"{t} {n}" for t, n in info["executions_per_type"].items())
    print(f"  executions  {info['executions']}  ({per})")
    hist = ", ".join(f"{n}: {c}" for n, c in info["sequence_length_histogram"].items())
    print(f"  lengths     {hist}")
    a = info["affordances_per_state"]
    per_type = ", ".join(f"{t} {v}" for t, v in a["per_type"].items())
    print(f"  affordances per state: mean {a['mean']} (min {a['min']}, max {a['max']}; {per_type})")
    fx = info["side_effects"]
    share = fx["executions"] / max(info["executions"], 1)
    per = ", ".join(
        f"{t} {n} ({n / max(info['executions_per_type'][t], 1):.0%})" for t, n in fx["per_type"].items()
    )
    print(f"  side effects {fx['executions']} executions ({share:.1%}; {per})")
    print("     by kind  " + ", ".join(f"{k} {n}" for k, n in fx["per_kind"].items()))
    if info["visibility"] is not None:
        v = info["visibility"]
        print(f"  hidden      present objects showing fewer than {v['min_pixels']} px, and what covers them:")
        for kind, row in v["per_kind"].items():
            cover = ", ".join(f"{c} {n}" for c, n in row["covered_by"].items())
            print(
                f"     {kind:8s} {row['hidden']} of {row['present']} ({row['share']:.2%})"
                + (f": {cover}" if cover else "")
            )
    print(f"  disk        {info['disk_bytes'] / 2**20:.1f} MiB")
    return 0


def cmd_data_show(args) -> int:
    from afford.data.format import Dataset
    from afford.viz.draw import draw_affordances, hstack, label, to_pil

    ds = Dataset(args.dir)
    indices = ds.indices(args.split)
    if not 0 <= args.index < len(indices):
        raise CLIError(f"--index {args.index}: the {args.split} split has {len(indices)} sequences")
    seq = ds.sequence(indices[args.index])
    panels = []
    for t in range(seq.length + 1):
        pil = to_pil(seq.image(t))
        if t < seq.length:
            a = seq.action(t)
            text = f"{t}: {a.type}" + (f" {a.turn:+g}" if a.turn else "")
            panels.append(label(draw_affordances(pil, [a]), text))
        else:
            held = seq.held[t]
            panels.append(label(pil, "final" + (f" (holding {seq.slots[held]})" if held >= 0 else "")))
    Path(args.out).parent.mkdir(parents=True, exist_ok=True)
    hstack(panels).save(args.out)
    print(f"{args.split} #{args.index} (sequence {seq.index}): {seq.length} executions; picture: {args.out}")
    return 0


def cmd_data_verify(args) -> int:
    from afford.data.format import verify

    problems, good = verify(args.dir, progress=not args.json)
    if args.json:
        print(json.dumps({"good_shards": good, "problems": problems}, indent=2))
    else:
        for p in problems:
            print(p)
        print(f"{args.dir}: {good} good shards, {len(problems)} bad or missing")
    return 1 if problems else 0


def cmd_data_predict(args) -> int:
    """Predicted states of a split, for `afford train recognition --predicted`."""
    import torch

    from afford.data.format import Dataset
    from afford.data.predicted import predict_states
    from afford.prediction.evaluate import load_net
    from afford.shipped import PREDICTION_FILE, WEIGHTS

    if args.sequences is not None and args.sequences < 1:
        raise CLIError("--sequences must be at least 1")
    data = Dataset(args.dir)
    checkpoint = Path(args.prediction) if args.prediction else WEIGHTS / PREDICTION_FILE
    net, config = load_net(checkpoint)
    torch.set_num_threads(config.training.threads)
    n = predict_states(
        net, data, args.split, args.out, args.sequences, progress=not args.json, source=str(checkpoint)
    )
    record = {"out": args.out, "states": n, "split": args.split}
    print(json.dumps(record, indent=2) if args.json else f"{args.out}: {n} predicted {args.split} states")
    return 0


def add_parsers(sub) -> None:
    g = sub.add_parser(
        "generate",
        help="generate a dataset of random scenes and affordance executions",
        description="Generate the paper's data (III.B): per sequence a random scene, then up to 4 "
        "executions of affordances drawn at random from the ground-truth list. Sequence i depends only "
        "on (seed, i): any worker count gives the same data. Shards are written whole or not at all; "
        "re-running the same command after an interruption makes only what is missing.",
    )
    g.add_argument("--out", required=True, metavar="DIR")
    g.add_argument("--sequences", type=int, required=True, metavar="N")
    g.add_argument("--seed", type=int, default=0)
    g.add_argument(
        "--workers", type=int, default=2, help="processes, or a local Ray instance's CPUs (default 2)"
    )
    g.add_argument(
        "--ray",
        nargs="?",
        const="",
        metavar="ADDRESS",
        help="run each shard as a Ray task (pip install 'afford[cluster]'): on a local instance, or "
        "with ADDRESS on a running cluster ('auto', or HEAD:6379 of `ray start --head`); the output "
        "folder must then be on storage every node sees",
    )
    g.add_argument("--shard-size", type=int, default=25, help="sequences per shard (default 25)")
    g.add_argument(
        "--turn-angles",
        choices=("quarter", "continuous"),
        default="quarter",
        help="quarter: every turn +90 or -90, the paper's (default); continuous: a random angle of "
        "either sign up to 180 degrees, to train a prediction net for continuous turns (paper V)",
    )
    g.add_argument(
        "--actions",
        choices=("uniform", "effects"),
        default="uniform",
        help="uniform: each execution drawn at random, the paper's (default); effects: each step "
        "tries up to 12 executions and keeps the first with a side effect (data/draws.py), so that "
        "a prediction net sees more of them (~40%% of executions, against ~12%%); not the paper's "
        "distribution",
    )
    g.add_argument(
        "--layout",
        choices=tuple(LAYOUTS),
        default="default",
        help="default: scenes as described in sim/layout.py, every dataset's; balances: the block "
        "always on one support up to 4.5 cm off its centre, with cups and balls on its ends, so "
        "that places and grasps near a tipping point are common; not the paper's distribution",
    )
    g.add_argument(
        "--poses-only",
        action="store_true",
        help="render nothing: store poses, held objects, affordance lists and the arm's path of "
        "each execution, with images of size 0; the same seed gives the same poses as with images. "
        "The data the object world model's dynamics learn from (`afford train dynamics`)",
    )
    g.add_argument(
        "--masks",
        action="store_true",
        help="also keep each state's instance mask (the object slot seen at each pixel, from MuJoCo's "
        "segmentation rendering): the ground truth the object perception net learns from",
    )
    g.add_argument(
        "--splits-of",
        type=int,
        metavar="M",
        help="hold out the val and test splits of an M-sequence dataset of the same seed (its first "
        "sequences are this one's), so that a smaller dataset is measured on the larger one's splits, "
        "e.g. --sequences 5200 --splits-of 10000 (default: this dataset's own)",
    )
    g.add_argument("--json", action="store_true", help="no progress bar; print a JSON report")
    g.set_defaults(func=cmd_generate)

    d = sub.add_parser("data", help="inspect a generated dataset", description="Inspect a dataset.")
    dsub = d.add_subparsers(dest="data", required=True)
    i = dsub.add_parser("info", help="counts, histograms, disk size", description="Summarise a dataset.")
    i.add_argument("dir", metavar="DIR")
    i.add_argument("--json", action="store_true")
    i.set_defaults(func=cmd_data_info)
    s = dsub.add_parser(
        "show",
        help="draw one sequence as a strip",
        description="Draw a sequence: each state with the affordance executed from it.",
    )
    s.add_argument("dir", metavar="DIR")
    s.add_argument("--split", choices=("train", "val", "test"), default="train")
    s.add_argument("--index", type=int, default=0, help="position within the split")
    s.add_argument("--out", default="out/sequence.png", metavar="FILE.png")
    s.set_defaults(func=cmd_data_show)
    v = dsub.add_parser(
        "verify",
        help="read every shard in full and list the bad ones",
        description="Read every shard (checksums and array consistency); list bad or missing shards. "
        "Exit status 1 if any.",
    )
    v.add_argument("dir", metavar="DIR")
    v.add_argument("--json", action="store_true")
    v.set_defaults(func=cmd_data_verify)
    p = dsub.add_parser(
        "predict",
        help="predicted states of a split, to train recognition on",
        description="Roll each sequence of a split out with a prediction net from its first state "
        "through its executed actions and write every predicted state to one .npz; each is labelled "
        "by the true state's affordances of the same step (`afford train recognition --predicted`).",
    )
    p.add_argument("dir", metavar="DIR")
    p.add_argument("--out", required=True, metavar="FILE.npz")
    p.add_argument("--split", choices=("train", "val", "test"), default="train")
    p.add_argument("--sequences", type=int, metavar="N", help="the split's first N sequences (default all)")
    p.add_argument(
        "--prediction", metavar="CHECKPOINT", help="prediction weights (default: the shipped ones)"
    )
    p.add_argument("--json", action="store_true")
    p.set_defaults(func=cmd_data_predict)
