"""`afford eval prediction`: the paper's Table 2 (IV.B) and Fig. 7-style pictures.

Every evaluated sequence is predicted from its first state through all its executions, each
step from the previous prediction. Per step: the mean absolute RGBD error over all pixels, and
over the pixels that changed in the ground truth (any channel by more than CHANGED).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import torch

from afford.data.format import Dataset
from afford.data.torch_data import PredictionData, collate_prediction
from afford.prediction.config import PredictionConfig
from afford.prediction.model import PredictionNet
from afford.training.checkpoint import load_net_from_checkpoint

KIND = "prediction"
CHANGED = 0.02  # a ground-truth pixel changed when a channel moved by more than this
TRAIN_SEQUENCES = 500
BATCH = 32


def load_net(path: str | Path) -> tuple[PredictionNet, PredictionConfig]:
    net, config, _ = load_net_from_checkpoint(path, KIND, PredictionConfig, PredictionNet)
    return net, config


@torch.no_grad()
def errors(net: PredictionNet, data: Dataset, split: str, limit: int | None = None):
    """Per run and step: (all-area error, changed-area error or NaN), the runs' sequence indices."""
    runs = PredictionData(data, split, max_steps=4, random_start=False)
    picks = (
        range(len(runs))
        if limit is None
        else np.linspace(0, len(runs) - 1, min(limit, len(runs))).astype(int)
    )
    picks = list(picks)
    all_err = np.full((len(picks), 4), np.nan)
    changed_err = np.full((len(picks), 4), np.nan)
    for b in range(0, len(picks), BATCH):
        images, actions, steps = collate_prediction([runs[int(k)] for k in picks[b : b + BATCH]])
        predicted = net.rollout(images[:, 0], actions)
        truth, before = images[:, 1:], images[:, :-1]
        abs_err = (predicted - truth).abs()  # (B, L, C, H, W)
        changed = ((truth - before).abs() > CHANGED).any(2, keepdim=True).expand_as(abs_err)
        for j in range(len(steps)):
            for s in range(int(steps[j])):
                all_err[b + j, s] = float(abs_err[j, s].mean())
                if changed[j, s].any():
                    changed_err[b + j, s] = float(abs_err[j, s][changed[j, s]].mean())
    return all_err, changed_err, [runs.indices[int(k)] for k in picks]


def _stats(values: np.ndarray) -> dict:
    v = values[~np.isnan(values)]
    return {
        "mean": float(v.mean()) if len(v) else None,
        "sd": float(v.std()) if len(v) else None,
        "n": int(len(v)),
    }


def table(all_err: np.ndarray, changed_err: np.ndarray) -> dict:
    out = {}
    for s in range(4):
        out[str(s + 1)] = {"all_area": _stats(all_err[:, s]), "changed_area": _stats(changed_err[:, s])}
    out["all"] = {"all_area": _stats(all_err.ravel()), "changed_area": _stats(changed_err.ravel())}
    return out


def evaluate(
    run: str | Path, data_dir: str | Path, checkpoint: str = "best.safetensors", pictures: bool = True
) -> dict:
    run = Path(run)
    net, config = load_net(run / checkpoint)
    torch.set_num_threads(config.threads)
    data = Dataset(data_dir)
    result = {"run": str(run), "checkpoint": checkpoint, "pixel_input": config.pixel_input}
    for split, limit in (("test", None), ("train", TRAIN_SEQUENCES)):
        all_err, changed_err, _ = errors(net, data, split, limit)
        result[split] = table(all_err, changed_err)
    if pictures:
        result["pictures"] = event_pictures(net, data, run / "predictions")
    return result


# ---------------------------------------------------------------------------- pictures
EVENTS = ("falls off the table", "cup topples", "cup turns with the block", "ball rolls away")


def find_events(data: Dataset, split: str = "test") -> dict[str, tuple[int, int]]:
    """The first (sequence, step) of each non-canonical effect, found from the true poses."""
    found: dict[str, tuple[int, int]] = {}
    for i in data.indices(split):
        seq = data.sequence(i)
        for t in range(seq.length):
            before, after = seq.poses[t], seq.poses[t + 1]
            act = seq.action(t)
            for k, slot in enumerate(seq.slots):
                was, now = not np.isnan(before[k, 0]), not np.isnan(after[k, 0])
                if was and not now and "falls off the table" not in found:
                    found["falls off the table"] = (i, t)
                if slot.startswith("cup") and was and now and seq.held[t + 1] != k:
                    if _upright(before[k]) and not _upright(after[k]) and "cup topples" not in found:
                        found["cup topples"] = (i, t)
                    moved = np.linalg.norm(after[k, :2] - before[k, :2]) > 0.03
                    # Carried round on the block: raised before and after, still upright (a cup
                    # flung off by the turn lands on the table or on its side).
                    carried = before[k, 2] > 0.06 and after[k, 2] > 0.06 and _upright(after[k])
                    if act.type == "turn" and moved and carried and "cup turns with the block" not in found:
                        found["cup turns with the block"] = (i, t)
                untouched = seq.held[t] != k and seq.held[t + 1] != k
                if slot.startswith("ball") and was and now and untouched and "ball rolls away" not in found:
                    if np.linalg.norm(after[k, :2] - before[k, :2]) > 0.05:
                        found["ball rolls away"] = (i, t)
        if len(found) == len(EVENTS):
            break
    return found


def _upright(pose: np.ndarray) -> bool:
    w, x, y, z = pose[3:7]
    up_z = 1 - 2 * (x * x + y * y)  # z component of the body's z axis
    return up_z > 0.9


@torch.no_grad()
def event_pictures(net: PredictionNet, data: Dataset, out: Path) -> dict[str, str]:
    """Fig. 7 style: the true sequence above the predicted one, for each kind of effect."""
    from afford.viz.draw import draw_affordances, hstack, label, to_pil, vstack

    out.mkdir(parents=True, exist_ok=True)
    paths = {}
    for name, (i, t) in find_events(data).items():
        seq = data.sequence(i)
        images = torch.from_numpy(np.stack([seq.image(k) for k in range(seq.length + 1)])).permute(0, 3, 1, 2)
        predicted = net.rollout(images[:1], torch.from_numpy(seq.actions)[None])[0]
        top, bottom = [], []
        for k in range(seq.length + 1):
            truth = to_pil(images[k].permute(1, 2, 0).numpy())
            text = "start" if k == 0 else f"{k}: after {seq.action(k - 1).type}"
            if k < seq.length:
                truth = draw_affordances(truth, [seq.action(k)])
            top.append(label(truth, ("true " if k else "") + text + (" <- " + name if k == t + 1 else "")))
            pred = images[0] if k == 0 else predicted[k - 1]
            bottom.append(label(to_pil(pred.permute(1, 2, 0).numpy()), "predicted" if k else "start"))
        path = out / f"{name.replace(' ', '-')}.png"
        vstack([hstack(top), hstack(bottom)]).save(path)
        paths[name] = str(path)
    return paths


def format_table(result: dict) -> str:
    lines = [f"pixel input: {'yes' if result['pixel_input'] else 'no'}", ""]
    lines.append(f"{'':6s} {'step':>5s} {'all area':>18s} {'changed area':>18s}")
    for split in ("test", "train"):
        for step, row in result[split].items():
            a, c = row["all_area"], row["changed_area"]
            cell = lambda s: "-" if s["mean"] is None else f"{s['mean']:.4f} ({s['sd']:.4f})"  # noqa: E731
            lines.append(f"{split:6s} {step:>5s} {cell(a):>18s} {cell(c):>18s}")
    return "\n".join(lines)
