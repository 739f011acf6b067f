"""Does the camera see what decides a place's side effect? (Issue: side effects, place.)

    python benchmarks/place_outcomes.py --data data/cpu [--json]

A place on the long block that tips it, or whose object falls or slides off, is the side effect
the prediction net foresees worst. The block rests on a support that it usually hides from the
top-down camera, so the offset that decides the lever is not in the image. This script reads
every place onto an elevated block in a dataset (true poses, data/effects.py) and counts how
often it had a side effect, grouped by what the camera does see: whether every support under
the block is hidden by it (its footprint inside the block's, seen from above), the kind placed,
how far out along the block (the centre, 5-9 cm, beyond 9 cm) and how many cups and balls
already stand on the block. A group whose rate is near 0 or 1 is decided by what is visible;
one near a half is an outcome the image cannot settle, where an uncertain prediction is the
right one.
"""

from __future__ import annotations

import argparse
import json
from collections import Counter

import numpy as np

CENTRE, FAR = 0.05, 0.09  # metres along the block from its centre: the centre place, the far end
DECIDED = 0.1  # a group with a rate within this of 0 or 1 is decided by what the camera sees


def block_axes(pose: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The unit vectors along and across an object's x axis, in the table's plane."""
    from afford.data.effects import planar_axes

    along, across = planar_axes(pose)
    norm = np.linalg.norm(along)
    return along / norm, across / norm


def covered(block: np.ndarray, support: np.ndarray) -> bool:
    """Is the support's top face inside the block's footprint, seen from above?"""
    from afford.sim.constants import BLOCK, SUPPORT

    along, across = block_axes(block)
    s_along, s_across = block_axes(support)
    corners = [
        support[:2] + i * SUPPORT.half[0] * s_along + j * SUPPORT.half[1] * s_across
        for i in (-1, 1)
        for j in (-1, 1)
    ]
    return all(
        abs((c - block[:2]) @ along) <= BLOCK.half[0] and abs((c - block[:2]) @ across) <= BLOCK.half[1]
        for c in corners
    )


def place_groups(poses: np.ndarray, actions: np.ndarray, steps: list, kinds: list[str]) -> list[tuple]:
    """(step index, visible group, had a side effect) for each place of one sequence onto an
    elevated block: poses (T, slots, 7), actions (T-1, 7), its effect labels, the slots' kinds."""
    from afford.data.effects import BLOCK_TIPS, PLACED_FALLS, PLACED_SLIDES, rested_on
    from afford.sim.affordance import Col
    from afford.sim.constants import BLOCK

    if "block" not in kinds:
        return []
    b = kinds.index("block")
    found = []
    for t, step in enumerate(steps):
        block = poses[t, b]
        if step.type != "place" or step.acted in (None, b) or np.isnan(block[0]):
            continue
        along, across = block_axes(block)
        offset = actions[t, Col.XY] - block[:2]
        out = abs(offset @ along)
        if abs(offset @ across) > BLOCK.half[1] or out > BLOCK.half[0]:
            continue  # placed elsewhere
        present = [j for j in range(len(kinds)) if not np.isnan(poses[t, j, 0])]
        under = [j for j in present if kinds[j] == "support" and rested_on(block, poses[t, j], "support")]
        if not under:
            continue  # the block on the table: nothing to tip
        load = sum(
            1
            for j in present
            if j not in (b, step.acted)
            and kinds[j] in ("cup", "ball")
            and rested_on(poses[t, j], block, "block")
        )
        group = (
            "hidden" if all(covered(block, poses[t, j]) for j in under) else "visible",
            kinds[step.acted],
            "centre" if out <= CENTRE else ("far end" if out > FAR else "near end"),
            load,
        )
        found.append((t, group, bool(step.kinds & {BLOCK_TIPS, PLACED_FALLS, PLACED_SLIDES})))
    return found


def count(root: str) -> tuple[Counter, Counter]:
    """Places onto an elevated block and those with a side effect, per visible group."""
    from afford.data.effects import slot_kind, summary_effects
    from afford.data.format import read_manifest, shard_path, shard_status, shard_summary

    manifest = read_manifest(root)
    slots = tuple(manifest.slots)
    kinds = [slot_kind(s) for s in slots]
    places, effects = Counter(), Counter()
    for shard in shard_status(root, manifest)[0]:
        summary = shard_summary(shard_path(root, shard))
        first = 0
        for q, (n, steps) in enumerate(
            zip(summary["state_count"], summary_effects(summary, slots), strict=True)
        ):
            poses = summary["poses"][first : first + n]
            actions = summary["actions"][first - q : first - q + n - 1]
            first += n
            for _, group, effect in place_groups(poses, actions, steps, kinds):
                places[group] += 1
                effects[group] += effect
    return places, effects


def head_probabilities(
    root: str, weights: str | None, split: str, limit: int | None = None
) -> dict[tuple, list[float]]:
    """The prediction net's (calibrated) probability of its side-effect outcome for each place
    of a split, predicted one step from the true state, per visible group."""
    import torch

    from afford.data.effects import sequence_effects, slot_kind
    from afford.data.format import Dataset
    from afford.images import to_chw
    from afford.shipped import Nets

    net = Nets(weights).predictor.eval()
    if net.config.outcomes.hypotheses < 2:
        raise SystemExit("place_outcomes: --weights needs a prediction net with two outcomes per step")
    torch.set_num_threads(net.config.training.threads)
    data = Dataset(root)
    probabilities: dict[tuple, list[float]] = {}
    for i in list(data.indices(split))[:limit]:
        seq = data.sequence(i)
        kinds = [slot_kind(s) for s in seq.slots]
        for t, group, _ in place_groups(seq.poses, seq.actions, sequence_effects(seq), kinds):
            image = to_chw(seq.image(t)[None])
            with torch.no_grad():
                latent, memory = net.encode(image)
                out = net.step_outcomes(latent, memory, image, torch.from_numpy(seq.actions[t][None]))
            probabilities.setdefault(group, []).append(float(out.probability[0, 1]))
    return probabilities


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--data", required=True, metavar="DIR")
    ap.add_argument(
        "--weights",
        metavar="DIR",
        nargs="?",
        const="",
        help="also the mean probability a two-outcome prediction net's head gives the side effect, "
        "per group, on --split (a weights folder; without DIR the shipped net)",
    )
    ap.add_argument("--split", default="test", choices=("train", "val", "test"))
    ap.add_argument("--limit", type=int, metavar="N", help="the head on the split's first N sequences only")
    ap.add_argument("--json", action="store_true")
    args = ap.parse_args()
    from afford.errors import UserError

    try:
        places, effects = count(args.data)
    except UserError as e:
        raise SystemExit(f"place_outcomes: {e}") from None
    heads = None
    if args.weights is not None:
        heads = head_probabilities(args.data, args.weights or None, args.split, args.limit)
    rows = []
    for g in sorted(places):
        row = {"supports": g[0], "placed": g[1], "where": g[2], "load": g[3], "places": places[g]}
        rows.append(row)
        row["side_effects"] = effects[g]
        if heads is not None:
            row["head"] = {
                "places": len(heads.get(g, [])),
                "mean": float(np.mean(heads[g])) if g in heads else None,
            }
    total = sum(effects.values())
    hidden = sum(v for g, v in effects.items() if g[0] == "hidden")
    decided = sum(
        effects[g] for g in places if min(effects[g] / places[g], 1 - effects[g] / places[g]) <= DECIDED
    )
    summary = {
        "side_effects": total,
        "over_hidden_supports": hidden,
        "in_decided_groups": decided,
        "groups": rows,
    }
    if args.json:
        print(json.dumps(summary, indent=1))
        return
    head = "" if heads is None else f"  the head's mean probability ({args.split}, places)"
    print(f"{'supports':9s} {'placed':7s} {'where':9s} {'load':>4s} {'places':>7s}  side-effect rate{head}")
    for r in rows:
        rate = r["side_effects"] / r["places"]
        line = f"{r['supports']:9s} {r['placed']:7s} {r['where']:9s} {r['load']:4d} {r['places']:7d}"
        line += f"  {rate:16.2f}"
        if heads is not None and r["head"]["mean"] is not None:
            line += f"  {r['head']['mean']:.2f} ({r['head']['places']})"
        print(line)
    print(
        f"side effects of places on an elevated block: {total}; over supports the block hides: "
        f"{hidden} ({hidden / max(total, 1):.0%}); in groups whose rate is within {DECIDED} of 0 or 1 "
        f"(decided by what the camera sees): {decided} ({decided / max(total, 1):.0%})"
    )


if __name__ == "__main__":
    from afford.errors import exit_on_user_error

    exit_on_user_error(main)
