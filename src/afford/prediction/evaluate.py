"""`afford eval prediction`: the paper's Table 2 (IV.B) and Fig. 7-style pictures.

Every evaluated sequence is predicted from its first state through all its executions, each
step from the previous prediction. Per step: the mean absolute RGBD error over all pixels, and
over the pixels that changed in the ground truth from the step before, under two masks: ours
(any channel moved by more than CHANGED) and the authors' (any change at all). Beside the net,
the same figures for copying the input (every step predicted as the start image): a net that
does not beat it has learned nothing of the effects.
"""

from __future__ import annotations

from functools import partial
from pathlib import Path

import numpy as np
import torch

from afford.data import effects as fx
from afford.data.format import Dataset
from afford.data.torch_data import PredictionData, collate_prediction
from afford.images import to_chw, to_hwc
from afford.prediction import foresight
from afford.prediction.config import CHANGED, PredictionConfig
from afford.prediction.model import PredictionNet
from afford.sim.affordances import TYPES
from afford.training.checkpoint import load_net_from_checkpoint

KIND = "prediction"
TRAIN_SEQUENCES = 500
BATCH = 32
STEPS = 4
# metric -> the changed-pixel threshold it averages over (None: all pixels)
METRICS = {"all_area": None, "changed_area": CHANGED, "changed_area_any": 0.0}
# The changed-area error of canonical steps and of steps with a side effect (errors()).
SPLIT_METRICS = ("changed_area_canonical", "changed_area_side")


def load_net(path: str | Path) -> tuple[PredictionNet, PredictionConfig]:
    """The prediction net in a checkpoint, and its config."""
    net, config, _ = load_net_from_checkpoint(path, KIND, PredictionConfig, PredictionNet)
    return net, config


@torch.no_grad()
def errors(net: PredictionNet | None, data: Dataset, split: str, limit: int | None = None):
    """Per metric, (runs, 4) errors per run and step (NaN where a run has no such step or no
    changed pixel), and the runs' sequence indices. `net` None: copy the input."""
    runs = PredictionData(data, split, max_steps=STEPS, random_start=False)
    picks = list(
        range(len(runs))
        if limit is None
        else np.linspace(0, len(runs) - 1, min(limit, len(runs))).astype(int)
    )
    out = {m: np.full((len(picks), STEPS), np.nan) for m in METRICS}
    side = np.zeros((len(picks), STEPS), bool)  # the step had a side effect (data/effects.py)
    for n, k in enumerate(picks):
        for t, step in enumerate(fx.sequence_effects(data.sequence(runs.indices[int(k)]))[:STEPS]):
            side[n, t] = not step.canonical
    for b in range(0, len(picks), BATCH):
        images, actions, steps = collate_prediction([runs[int(k)] for k in picks[b : b + BATCH]])
        truth, before = images[:, 1:], images[:, :-1]
        if net is None:
            predicted = images[:, :1].expand_as(truth)
        else:
            predicted = net.rollout(images[:, 0], actions, steps)
        abs_err = (predicted - truth).abs().mean(2)  # (B, L, H, W)
        moved = (truth - before).abs().amax(2)  # (B, L, H, W)
        for j in range(len(steps)):
            for s in range(int(steps[j])):
                for metric, threshold in METRICS.items():
                    err = abs_err[j, s]
                    if threshold is not None:
                        err = err[moved[j, s] > threshold]
                    if err.numel():
                        out[metric][b + j, s] = float(err.mean())
    # Table 2's changed-area error split by what the step did: canonical steps, side-effect steps.
    changed = out["changed_area"]
    out["changed_area_canonical"] = np.where(side, np.nan, changed)
    out["changed_area_side"] = np.where(side, changed, np.nan)
    return out, [runs.indices[int(k)] for k in picks]


def _stats(values: np.ndarray) -> dict:
    v = values[~np.isnan(values)]
    return {
        "mean": float(v.mean()) if len(v) else None,
        "sd": float(v.std()) if len(v) else None,
        "n": int(len(v)),
    }


def table(errs: dict[str, np.ndarray]) -> dict:
    out = {}
    for s in range(STEPS):
        out[str(s + 1)] = {m: _stats(e[:, s]) for m, e in errs.items()}
    out["all"] = {m: _stats(e.ravel()) for m, e in errs.items()}
    return out


def evaluate_world(
    world, name: str, data_dir: str | Path, pictures: Path | None = None, recognizer=None
) -> dict:
    """Table 2, foresight, recognition on predicted states and Fig. 7-style pictures for any
    world model with a prediction net's `rollout` (e.g. objects/rollout.py's), as for a net."""
    data = Dataset(data_dir)
    result: dict = {"world_model": name}
    for split, limit in (("test", None), ("train", TRAIN_SEQUENCES)):
        result[split] = table(errors(world, data, split, limit)[0])
        result[f"{split}_copy"] = table(errors(None, data, split, limit)[0])
    result["foresight"] = foresight.measure(world.rollout, data, "test").as_dict()
    if recognizer is not None:
        from afford.prediction.futures import future_recall, net_predictor

        result["future_recall"] = future_recall(net_predictor(world), recognizer, data, "test")
    if pictures is not None:
        result["pictures"] = event_pictures(world, data, pictures)
    return result


def evaluate(
    checkpoint: str | Path, data_dir: str | Path, pictures: Path | None = None, recognizer=None
) -> dict:
    """Table 2 for the net in `checkpoint`, and the copy baseline, on test and train; with a
    recogniser, also recognition on the predicted test states (`futures.py`)."""
    net, config = load_net(checkpoint)
    torch.set_num_threads(config.training.threads)
    data = Dataset(data_dir)
    result = {
        "checkpoint": str(checkpoint),
        "architecture": config.model.architecture,
        "pixel_input": config.model.pixel_input,
    }
    for split, limit in (("test", None), ("train", TRAIN_SEQUENCES)):
        result[split] = table(errors(net, data, split, limit)[0])
        result[f"{split}_copy"] = table(errors(None, data, split, limit)[0])
    result["foresight"] = foresight.measure(net.rollout, data, "test").as_dict()
    if config.outcomes.hypotheses > 1:  # each outcome forced: what the head's pick gains or loses
        result["foresight_forced"] = [
            foresight.measure(partial(forced, net, k), data, "test").as_dict()
            for k in range(config.outcomes.hypotheses)
        ]
    if config.outcomes.hypotheses == 2 and config.outcomes.hypotheses_by == "effect":
        from afford.prediction.calibration import calibrate

        result["choice_head"] = calibrate(net, data)
    if recognizer is not None:
        from afford.prediction.futures import future_recall, net_predictor

        result["future_recall"] = future_recall(net_predictor(net), recognizer, data, "test")
    if pictures is not None:
        result["pictures"] = event_pictures(net, data, pictures)
    return result


def forced(net: PredictionNet, k: int, images: torch.Tensor, actions: torch.Tensor) -> torch.Tensor:
    """A many-outcome net's rollout with its k-th outcome drawn at every step, whatever its
    head picks (the state carried on is still the head's)."""
    with torch.no_grad():
        return net.rollout_hypotheses(images, actions).candidates[:, :, k]


# ---------------------------------------------------------------------------- pictures
# The canonical effects (the first step executing that type with no side effect), then one of
# each kind of side effect (data/effects.py).
EVENTS = (*TYPES, *fx.KINDS)


def find_events(data: Dataset, split: str = "test") -> dict[str, tuple[int, int]]:
    """The first (sequence, step) of each event of EVENTS in a split."""
    found: dict[str, tuple[int, int]] = {}
    for i in data.indices(split):
        seq = data.sequence(i)
        for t, step in enumerate(fx.sequence_effects(seq)):
            for name in step.kinds or {step.type}:
                found.setdefault(name, (i, t))
        if len(found) == len(EVENTS):
            break
    return found


@torch.no_grad()
def event_pictures(net: PredictionNet, data: Dataset, out: Path) -> dict[str, str]:
    """Fig. 7 style: the true sequence above the predicted one, for each kind of effect."""
    from afford.viz.draw import draw_affordances, hstack, label, to_pil, vstack

    out.mkdir(parents=True, exist_ok=True)
    paths = {}
    for name, (i, t) in find_events(data).items():
        seq = data.sequence(i)
        images = to_chw(np.stack([seq.image(k) for k in range(seq.length + 1)]))
        predicted = net.rollout(images[:1], torch.from_numpy(seq.actions)[None])[0]
        top, bottom = [], []
        for k in range(seq.length + 1):
            truth = to_pil(to_hwc(images[k]))
            text = "start" if k == 0 else f"{k}: after {seq.action(k - 1).type}"
            if k < seq.length:
                truth = draw_affordances(truth, [seq.action(k)])
            top.append(label(truth, ("true " if k else "") + text + (" <- " + name if k == t + 1 else "")))
            pred = images[0] if k == 0 else predicted[k - 1]
            bottom.append(label(to_pil(to_hwc(pred)), "predicted" if k else "start"))
        path = out / f"{name.replace(' ', '-')}.png"
        vstack([hstack(top), hstack(bottom)]).save(path)
        paths[name] = str(path)
    return paths


def format_table(result: dict) -> str:
    def cell(s: dict) -> str:
        return "-" if s["mean"] is None else f"{s['mean']:.4f} ({s['sd']:.4f})"

    if "world_model" in result:
        lines = [f"world model: {result['world_model']}", ""]
    else:
        lines = [f"{result['architecture']} net, pixel input: {'yes' if result['pixel_input'] else 'no'}", ""]
    names = {
        "all_area": "all area",
        "changed_area": f"changed > {CHANGED}",
        "changed_area_any": "changed at all",
        "changed_area_canonical": "canonical steps",
        "changed_area_side": "side-effect steps",
    }
    metrics = (*METRICS, *SPLIT_METRICS)
    lines.append(f"{'':11s} {'step':>4s} " + " ".join(f"{names[m]:>18s}" for m in metrics))
    for split in ("test", "train"):
        for who in (split, f"{split}_copy"):
            for step, row in result[who].items():
                lines.append(f"{who:11s} {step:>4s} " + " ".join(f"{cell(row[m]):>18s}" for m in metrics))
    if "foresight" in result:
        lines += [
            "",
            "foresight, one step from the true state (1: the truth drawn, 0: no better than a copy):",
        ]
        lines.append(foresight.format_foresight(result["foresight"]))
    for k, forced_k in enumerate(result.get("foresight_forced", ())):
        lines += ["", f"the same with outcome {k + 1} drawn at every step, whatever the head picks:"]
        lines.append(foresight.format_foresight(forced_k))
    if "future_recall" in result:
        from afford.prediction.futures import format_futures

        lines += [
            "",
            "recognition on predicted test states (Table 1's criteria):",
            format_futures(result["future_recall"]),
        ]
    return "\n".join(lines)
