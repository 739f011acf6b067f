"""How well perception sees the objects, against the simulator's truth.

An object is visible when at least `VISIBLE_PX` pixels of the image show it (a ball inside a
cup is not). Perceived and visible objects are matched greedily, nearest first, within
`MATCH_PX` of the true centre's projection, whatever their kinds; then the measures are read
off the matched pairs. An object that shows 1 to `VISIBLE_PX` - 1 pixels is in neither count.
"""

from __future__ import annotations

import time

import numpy as np

from afford.data.format import Dataset
from afford.objects.perceive import SeenObject, perceive
from afford.objects.perception import PerceptionNet
from afford.objects.perception_train import states_of
from afford.objects.state import KINDS, N_SLOTS, SLOT_KIND, posture, quat_axes
from afford.sim.camera import world_to_pixel

VISIBLE_PX = 20
MATCH_PX = 5.0
SPEED_BATCH = 256


def match(objects: list[SeenObject], poses: np.ndarray, mask: np.ndarray) -> dict[int, int]:
    """{true slot: index in objects} for the visible slots matched, nearest pairs first."""
    visible = [s for s in range(N_SLOTS) if not np.isnan(poses[s, 0]) and (mask == s).sum() >= VISIBLE_PX]
    return _nearest(objects, list(range(len(objects))), poses, visible)


def _nearest(
    objects: list[SeenObject], which: list[int], poses: np.ndarray, slots: list[int]
) -> dict[int, int]:
    """{slot: index in objects} pairing `slots` with the objects at `which`, nearest first."""
    if not which or not slots:
        return {}
    true_px = world_to_pixel(poses[slots, :3].astype(float))
    seen_px = np.array([objects[j].pixel for j in which])
    d = np.linalg.norm(true_px[:, None] - seen_px[None], axis=-1)
    pairs: dict[int, int] = {}
    for flat in np.argsort(d, axis=None):
        i, j = np.unravel_index(flat, d.shape)
        if d[i, j] > MATCH_PX:
            break
        if slots[i] not in pairs and which[j] not in pairs.values():
            pairs[slots[i]] = which[j]
    return pairs


def aligned_state(objects: list[SeenObject], poses: np.ndarray, mask: np.ndarray) -> tuple[np.ndarray, int]:
    """Perceived objects as a state whose slots are those of the true objects they match: the
    dynamics measured from perceived states are scored object by object against the truth."""
    out = np.full((N_SLOTS, 7), np.nan, np.float32)
    held, best = -1, 0.5
    pairs = match(objects, poses, mask)
    for slot, j in pairs.items():
        out[slot] = np.concatenate([objects[j].position, objects[j].quat])
        if objects[j].held > best:
            held, best = slot, objects[j].held
    return out, held


def perceived_starts(net: PerceptionNet, data: Dataset, t) -> tuple[np.ndarray, np.ndarray]:
    """Each execution of `t` (Transitions of `data`) started from the state the perception net
    sees in its start image: poses (N, slots, 7) in the slots of the true objects they match
    (NaN: not found) and held slots (N,). The dataset needs images and instance masks."""
    from afford.data.format import DataError

    before = np.full_like(t.before, np.nan)
    held = np.full_like(t.held_before, -1)
    for start in range(0, len(t), SPEED_BATCH):
        rows = range(start, min(start + SPEED_BATCH, len(t)))
        seqs = [data.sequence(int(t.sequence[r])) for r in rows]
        steps = [int(t.step[r]) for r in rows]
        seen = perceive(net, np.stack([s.image(k) for s, k in zip(seqs, steps, strict=True)]))
        for r, s, k, objects in zip(rows, seqs, steps, seen, strict=True):
            if s.masks is None:
                raise DataError(
                    f"{data.root}: no instance masks, needed to match perceived objects to true ones"
                )
            before[r], held[r] = aligned_state(objects, s.poses[k], s.masks[k])
    return before, held


def measure_perception(
    net: PerceptionNet, data: Dataset, split: str | None, limit: int | None = None
) -> dict:
    items = states_of(data, split)
    if limit is not None and limit < len(items):
        items = [items[i] for i in np.linspace(0, len(items) - 1, limit).astype(int)]
    visible = found = spurious = kind_right = posture_n = posture_right = held_right = 0
    px_err, mm_err, ious, tilt_err = [], [], [], []
    # Per true posture and per kind: where the shares above are lost.
    by_posture = {name: [0, 0] for name in ("upright", "tipped", "lying")}
    by_kind = {kind: [0, 0] for kind in KINDS}
    seconds = 0.0
    for start in range(0, len(items), SPEED_BATCH):
        chunk = items[start : start + SPEED_BATCH]
        seqs = [data.sequence(i) for i, _ in chunk]
        images = np.stack([s.image(t) for s, (_, t) in zip(seqs, chunk, strict=True)])
        t0 = time.perf_counter()
        seen = perceive(net, images)
        seconds += time.perf_counter() - t0
        for s, (_, t), objects in zip(seqs, chunk, seen, strict=True):
            poses, mask = s.poses[t], s.masks[t]
            pairs = match(objects, poses, mask)
            vis = [k for k in range(N_SLOTS) if not np.isnan(poses[k, 0]) and (mask == k).sum() >= VISIBLE_PX]
            visible += len(vis)
            for k in vis:
                by_kind[KINDS[SLOT_KIND[k]]][0] += 1
                by_kind[KINDS[SLOT_KIND[k]]][1] += k in pairs
            found += len(pairs)
            spurious += len(objects) - len(pairs)
            held_seen = -1
            for slot, j in pairs.items():
                o = objects[j]
                kind_right += o.kind == KINDS[SLOT_KIND[slot]]
                px_err.append(float(np.linalg.norm(o.pixel - world_to_pixel(poses[slot, :3].astype(float)))))
                mm_err.append(float(np.linalg.norm(o.position - poses[slot, :3])) * 1000)
                truth = mask == slot
                ious.append(float((truth & o.mask).sum() / max((truth | o.mask).sum(), 1)))
                up, along = quat_axes(poses[slot, 3:7].astype(float))
                if KINDS[SLOT_KIND[slot]] != "ball":
                    posture_n += 1
                    true_posture = posture(float(up[2]))
                    posture_right += o.posture == true_posture
                    by_posture[true_posture][0] += 1
                    by_posture[true_posture][1] += o.posture == true_posture
                if KINDS[SLOT_KIND[slot]] == "block":
                    tilt_err.append(
                        abs(
                            np.degrees(np.arcsin(min(1, abs(along[2]))))
                            - np.degrees(np.arcsin(min(1, abs(o.along[2]))))
                        )
                    )
                if o.held > 0.5 and (held_seen < 0 or o.held > objects[pairs[held_seen]].held):
                    held_seen = slot
            held_right += held_seen == int(s.held[t])
    px = np.array(px_err)
    return {
        "images": len(items),
        "visible_objects": visible,
        "found": found / max(visible, 1),
        "spurious_per_image": spurious / max(len(items), 1),
        "kind_right": kind_right / max(found, 1),
        "position_median_px": float(np.median(px)) if len(px) else None,
        "position_p95_px": float(np.percentile(px, 95)) if len(px) else None,
        "position_median_mm": float(np.median(mm_err)) if mm_err else None,
        "posture_right": posture_right / max(posture_n, 1),
        "posture_right_by_truth": {k: {"n": n, "right": r / max(n, 1)} for k, (n, r) in by_posture.items()},
        "found_by_kind": {k: {"n": n, "found": f / max(n, 1)} for k, (n, f) in by_kind.items()},
        "block_tilt_median_deg": float(np.median(tilt_err)) if tilt_err else None,
        "mask_iou_mean": float(np.mean(ious)) if ious else None,
        "held_right": held_right / max(len(items), 1),
        "images_per_second": len(items) / seconds if seconds else None,
    }


def perception_table(r: dict) -> str:
    def f(key: str, digits: int) -> str:
        return "n/a" if r[key] is None else f"{r[key]:.{digits}f}"

    rows = [
        ("images", f"{r['images']}"),
        ("visible objects", f"{r['visible_objects']}"),
        ("found", f("found", 4)),
        *((f"  {k}s (n {v['n']})", f"{v['found']:.4f}") for k, v in r.get("found_by_kind", {}).items()),
        ("spurious per image", f("spurious_per_image", 3)),
        ("kind right", f("kind_right", 4)),
        ("position median / p95 (px)", f"{f('position_median_px', 2)} / {f('position_p95_px', 2)}"),
        ("position median (mm, 3D)", f("position_median_mm", 1)),
        ("upright / tipped / lying right", f("posture_right", 4)),
        *(
            (f"  of the {k} (n {v['n']})", f"{v['right']:.4f}")
            for k, v in r.get("posture_right_by_truth", {}).items()
        ),
        ("block tilt median error (deg)", f("block_tilt_median_deg", 2)),
        ("mask IoU (mean)", f("mask_iou_mean", 4)),
        ("held object right", f("held_right", 4)),
        ("images / s (batches of 256)", f("images_per_second", 0)),
    ]
    return "\n".join(f"{k:32s} {v}" for k, v in rows)
