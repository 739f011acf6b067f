"""Recognition on predicted futures: how many of the true state's affordances the recognition
net finds on the predicted one (Table 1's criteria, paper IV.A), step by step.

This is what the planner (II.D) relies on, and what the paper does not measure: the planner
expands its tree from affordances recognised on predicted states. Each test sequence is rolled
out from its start image through its executed actions; the recogniser runs on every predicted
state and, for comparison, on the true state of the same step; both are scored against the
true state's ground-truth affordance list.

A predictor maps a run (its true images (B, L+1, C, H, W), actions (B, L, 7), steps (B,)) to
the predicted states (B, L, C, H, W). The net sees only the first image; the baselines
(copying the start, the truth itself) show the range a net falls in.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import numpy as np
import torch

from afford.data.format import Dataset
from afford.data.torch_data import PredictionData, collate_prediction
from afford.images import to_hwc
from afford.metrics import Tally
from afford.recognition.infer import Recognizer
from afford.sim.affordance import decode_affordance

STEPS = 4
BATCH = 32
PICTURES = 4  # test sequences drawn by `afford eval futures`

Predictor = Callable[[torch.Tensor, torch.Tensor, torch.Tensor], torch.Tensor]


def net_predictor(net) -> Predictor:
    """The prediction net: from the first image only, through the executed actions."""
    return lambda images, actions, steps: net.rollout(images[:, 0], actions, steps)


# name -> predictor for the baselines
BASELINES: dict[str, Predictor] = {
    "copy": lambda images, actions, steps: images[:, :1].expand(-1, actions.shape[1], -1, -1, -1),
    "truth": lambda images, actions, steps: images[:, 1 : actions.shape[1] + 1],
}


def _runs(data: Dataset, split: str, limit: int | None) -> tuple[PredictionData, list[int]]:
    runs = PredictionData(data, split, max_steps=STEPS, random_start=False)
    n = len(runs)
    picks = list(range(n)) if limit is None else np.linspace(0, n - 1, min(limit, n)).astype(int).tolist()
    return runs, picks


def future_recall(
    predict: Predictor, recognizer: Recognizer, data: Dataset, split: str = "test", limit: int | None = None
) -> dict:
    """Per step 1-4: Table 1 on the predicted states and on the true states."""
    return future_recalls({"net": predict}, recognizer, data, split, limit)["net"]


@torch.no_grad()
def future_recalls(
    predictors: dict[str, Predictor],
    recognizer: Recognizer,
    data: Dataset,
    split: str = "test",
    limit: int | None = None,
) -> dict[str, dict]:
    """`future_recall` for several predictors on the same runs; the true states are
    recognised once for all of them."""
    runs, picks = _runs(data, split, limit)
    predicted_tally = {name: [Tally() for _ in range(STEPS)] for name in predictors}
    true_tally = [Tally() for _ in range(STEPS)]
    for b in range(0, len(picks), BATCH):
        chunk = picks[b : b + BATCH]
        images, actions, steps = collate_prediction([runs[k] for k in chunk])
        predicted = {name: predict(images, actions, steps) for name, predict in predictors.items()}
        for s in range(STEPS):
            rows = [j for j in range(len(chunk)) if steps[j] > s]
            if not rows:
                continue
            truths = [
                [decode_affordance(r) for r in data.sequence(runs.indices[chunk[j]]).affordances[s + 1]]
                for j in rows
            ]
            for j, found in enumerate(recognizer(images[rows, s + 1])):
                true_tally[s].add(found, truths[j])
            for name, states in predicted.items():
                for j, found in enumerate(recognizer(states[rows, s])):
                    predicted_tally[name][s].add(found, truths[j])
    return {
        name: {
            str(s + 1): {"predicted": tallies[s].table(), "true": true_tally[s].table()}
            for s in range(STEPS)
            if true_tally[s].images
        }
        for name, tallies in predicted_tally.items()
    }


@torch.no_grad()
def pictures(
    predict: Predictor, recognizer: Recognizer, data: Dataset, out: Path, n: int = PICTURES
) -> list[str]:
    """Fig. 6 style on futures: per test sequence, the true states with their detections above
    the predicted states with theirs."""
    from afford.viz.draw import draw_affordances, hstack, label, to_pil, vstack

    out.mkdir(parents=True, exist_ok=True)
    runs, picks = _runs(data, "test", n)
    paths = []
    for k in picks:
        images, actions, steps = collate_prediction([runs[k]])
        predicted = predict(images, actions, steps)[0]
        length = int(steps[0])
        true_found = recognizer(images[0, 1 : length + 1])
        pred_found = recognizer(predicted[:length])
        top, bottom = [], []
        for s in range(length):
            act = decode_affordance(actions[0, s].numpy()).type
            truth = to_pil(to_hwc(images[0, s + 1]))
            pred = to_pil(to_hwc(predicted[s]))
            top.append(
                label(
                    draw_affordances(truth, [d.affordance for d in true_found[s]]),
                    f"{s + 1}: after {act}, true",
                )
            )
            bottom.append(label(draw_affordances(pred, [d.affordance for d in pred_found[s]]), "predicted"))
        path = out / f"futures-{runs.indices[k]:05d}.png"
        vstack([hstack(top), hstack(bottom)]).save(path)
        paths.append(str(path))
    return paths


def format_futures(result: dict) -> str:
    lines = [
        f"{'step':>4s} {'recall, predicted':>18s} {'spurious':>9s} {'recall, true':>13s} {'spurious':>9s}"
    ]
    for step, r in result.items():
        p, t = r["predicted"], r["true"]
        lines.append(
            f"{step:>4s} {p['recall']['all']['recall']:18.3f} {p['spurious_per_image']:9.2f} "
            f"{t['recall']['all']['recall']:13.3f} {t['spurious_per_image']:9.2f}"
        )
    return "\n".join(lines)


def format_report(result: dict) -> str:
    """`afford eval futures`: recall (spurious per image) per step on the net's predicted
    states, on the start image copied forward, and on the true states."""

    def cell(t: dict) -> str:
        return f"{t['recall']['all']['recall']:.3f} ({t['spurious_per_image']:.2f})"

    lines = [
        f"cut-off {result['threshold']:.2f}; recall (spurious per image), Table 1's criteria",
        f"{'step':>4s} {'predicted':>14s} {'copy start':>14s} {'true state':>14s}",
    ]
    for step, r in result["net"].items():
        copy = result["copy"][step]["predicted"]
        lines.append(f"{step:>4s} {cell(r['predicted']):>14s} {cell(copy):>14s} {cell(r['true']):>14s}")
    return "\n".join(lines)
