"""Recognition on predicted futures: how many of the true next state's affordances the
recognition net finds on the predicted one (Table 1's criteria, paper IV.A).

This is what the planner (II.D) relies on: it expands its tree from affordances recognised on
predicted states. Each test sequence is rolled out from its start image through its executed
actions; the recogniser runs on every predicted state and, for comparison, on the true state
of the same step; both are scored against the true state's ground-truth affordance list.
"""

from __future__ import annotations

import numpy as np
import torch

from afford.data.format import Dataset, decode_affordance
from afford.data.torch_data import PredictionData, collate_prediction
from afford.prediction.model import PredictionNet
from afford.recognition.infer import Recognizer
from afford.recognition.metrics import Tally

STEPS = 4
BATCH = 32


@torch.no_grad()
def future_recall(
    net: PredictionNet, recognizer: Recognizer, data: Dataset, split: str = "test", limit: int | None = None
) -> dict:
    """Per step 1-4: Table 1 on the predicted states and on the true states."""
    runs = PredictionData(data, split, max_steps=STEPS, random_start=False)
    picks = list(
        range(len(runs))
        if limit is None
        else np.linspace(0, len(runs) - 1, min(limit, len(runs))).astype(int)
    )
    predicted_tally = [Tally() for _ in range(STEPS)]
    true_tally = [Tally() for _ in range(STEPS)]
    for b in range(0, len(picks), BATCH):
        chunk = [int(k) for k in picks[b : b + BATCH]]
        images, actions, steps = collate_prediction([runs[k] for k in chunk])
        predicted = net.rollout(images[:, 0], actions, steps)
        for s in range(STEPS):
            rows = [j for j in range(len(chunk)) if steps[j] > s]
            if not rows:
                continue
            found_pred = recognizer(predicted[rows, s])
            found_true = recognizer(images[rows, s + 1])
            for j, dp, dt in zip(rows, found_pred, found_true, strict=True):
                seq = data.sequence(runs.indices[chunk[j]])
                truths = [decode_affordance(r) for r in seq.affordances[s + 1]]
                predicted_tally[s].add(dp, truths)
                true_tally[s].add(dt, truths)
    return {
        str(s + 1): {"predicted": predicted_tally[s].table(), "true": true_tally[s].table()}
        for s in range(STEPS)
        if true_tally[s].images
    }


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
