"""Where the pixels of the objects' masks go: per kind, what the perception net's masks miss,
where the missed pixels went, and which objects' masks are poor.

    python benchmarks/perception_masks.py [--weights FILE] [--data data/objects-test] \
        [--every 10] [--json]

For every matched object (perception_measure.match: a visible object and the perceived one
nearest it) of every `--every`-th sequence's state images, the true mask against the perceived
one: its recall and precision, and its missed pixels sorted by where they lie (on the true
mask's edge, a pixel with a neighbour outside it, or inside) and by what the net's kind map
called them (background, another kind, or this kind but joined to no object or another one).
It also gives the mean IoU, the share of objects whose IoU is under POOR_IOU, and the mean IoU
of the rest: how much of the shortfall is edges and how much a tail of whole objects.
"""

from __future__ import annotations

import argparse
import json
import sys

import numpy as np

from afford.errors import UserError

POOR_IOU = 0.7  # an object's mask below this IoU is counted among the poor ones


def edge_of(mask: np.ndarray) -> np.ndarray:
    """The pixels of `mask` with a 4-neighbour outside it."""
    inner = mask.copy()
    inner[1:] &= mask[:-1]
    inner[:-1] &= mask[1:]
    inner[:, 1:] &= mask[:, :-1]
    inner[:, :-1] &= mask[:, 1:]
    return mask & ~inner


def measure(weights: str, data_dir: str, every: int) -> dict[str, dict[str, float]]:
    import torch
    from tqdm import tqdm

    from afford.data.format import Dataset
    from afford.objects.perceive import perceive
    from afford.objects.perception import CHANNELS
    from afford.objects.perception_measure import match
    from afford.objects.perception_train import load_perception
    from afford.objects.state import KINDS, SLOT_KIND

    net = load_perception(weights)
    data = Dataset(data_dir)
    names = (
        "true",
        "missed",
        "missed_edge",
        "missed_background",
        "missed_other_kind",
        "missed_own_kind",
        "edge",
        "seen",
        "spill",
    )
    sums = {k: dict.fromkeys(names, 0.0) for k in KINDS}
    ious: dict[str, list[float]] = {k: [] for k in KINDS}
    for i in tqdm(range(0, len(data), every), desc="masks", unit="seq"):
        seq = data.sequence(i)
        if seq.masks is None:
            raise UserError(f"{data_dir}: no instance masks; make it with `afford generate --masks`")
        images = np.stack([seq.image(t) for t in range(seq.length + 1)])
        with torch.no_grad():
            out = net.stacked(torch.from_numpy(images.astype(np.float32)).permute(0, 3, 1, 2))
        kind_maps = out[:, CHANNELS["seg"]].argmax(1).numpy()
        for t, objects in enumerate(perceive(net, images)):
            for slot, j in match(objects, seq.poses[t], seq.masks[t]).items():
                kind = int(SLOT_KIND[slot])
                true, seen = seq.masks[t] == slot, objects[j].mask
                missed = true & ~seen
                called = kind_maps[t][missed]
                s = sums[KINDS[kind]]
                s["true"] += true.sum()
                s["missed"] += missed.sum()
                s["missed_edge"] += (missed & edge_of(true)).sum()
                s["missed_background"] += (called == 0).sum()
                s["missed_other_kind"] += ((called != 0) & (called != kind + 1)).sum()
                s["missed_own_kind"] += (called == kind + 1).sum()
                s["edge"] += edge_of(true).sum()
                s["seen"] += seen.sum()
                s["spill"] += (seen & ~true).sum()
                ious[KINDS[kind]].append(float((true & seen).sum() / (true | seen).sum()))
    report = {}
    for kind, s in sums.items():
        iou = np.array(ious[kind])
        if not len(iou):
            continue
        missed = max(s["missed"], 1)
        report[kind] = {
            "objects": len(iou),
            "pixels_per_object": s["true"] / len(iou),
            "edge_share_of_pixels": s["edge"] / s["true"],
            "recall": 1 - s["missed"] / s["true"],
            "precision": 1 - s["spill"] / max(s["seen"], 1),
            "missed_on_edge": s["missed_edge"] / missed,
            "missed_called_background": s["missed_background"] / missed,
            "missed_called_other_kind": s["missed_other_kind"] / missed,
            "missed_own_kind_other_object": s["missed_own_kind"] / missed,
            "iou_mean": float(iou.mean()),
            "poor_share": float((iou < POOR_IOU).mean()),
            "iou_mean_of_the_rest": float(iou[iou >= POOR_IOU].mean()) if (iou >= POOR_IOU).any() else 0.0,
        }
    return report


def main(argv: list[str] | None = None) -> int:
    from afford.shipped import OBJECTS, PERCEPTION_FILE

    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--weights", default=str(OBJECTS / PERCEPTION_FILE), help="a perception net")
    p.add_argument("--data", default="data/objects-test", help="a dataset with instance masks")
    p.add_argument("--every", type=int, default=10, help="measure every n-th sequence")
    p.add_argument("--json", action="store_true", help="print a JSON report")
    args = p.parse_args(argv)
    try:
        report = measure(args.weights, args.data, args.every)
    except (UserError, FileNotFoundError) as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    if args.json:
        print(json.dumps(report, indent=2))
        return 0
    print(
        f"{'kind':8} {'n':>5} {'px':>6} {'recall':>7} {'prec.':>6} {'IoU':>6} {'poor':>6} {'rest':>6}"
        f" | missed: {'edge':>5} {'bg':>5} {'other':>6} {'own':>5}"
    )
    for kind, r in report.items():
        print(
            f"{kind:8} {r['objects']:5d} {r['pixels_per_object']:6.0f}"
            f" {r['recall']:7.3f} {r['precision']:6.3f}"
            f" {r['iou_mean']:6.3f} {r['poor_share']:6.3f} {r['iou_mean_of_the_rest']:6.3f} |"
            f"         {r['missed_on_edge']:5.2f} {r['missed_called_background']:5.2f}"
            f" {r['missed_called_other_kind']:6.2f} {r['missed_own_kind_other_object']:5.2f}"
        )
    return 0


if __name__ == "__main__":
    sys.exit(main())
