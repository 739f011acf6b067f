"""`afford eval goals`: the agreement model's ROC AUC per relation, on true and predicted states.

For every state of the test split (and every predicted state of a file made from the test split
by `afford data predict`), clauses are drawn about the true state, half true, with a fixed
stream; the model scores each against the image (the true one, or the prediction). AUC per
relation: how often a true clause of that relation outscores a false one.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import torch

from afford.data.format import DataError, Dataset
from afford.data.predicted import PredictedStates
from afford.metrics import roc_auc
from afford.words.data import ClauseData, collate_clauses
from afford.words.facts import RELATION_NAMES
from afford.words.model import AgreementNet

DRAWS_PER_STATE = 4
BATCH = 128
PREDICTED_STEPS = (1, 2, 3)  # the must-show's depths


@torch.no_grad()
def scores(net: AgreementNet, data: ClauseData, picks: list[int], seed: int = 0, progress: bool = True):
    """(logits, truths, relation ids) of DRAWS_PER_STATE clauses for each item in `picks`."""
    from tqdm import tqdm

    data.rng = np.random.default_rng(seed)
    draws = [k for k in picks for _ in range(DRAWS_PER_STATE)]
    out = ([], [], [])
    for b in tqdm(range(0, len(draws), BATCH), disable=not progress, desc="score", unit="batch", leave=False):
        batch = collate_clauses([data[k] for k in draws[b : b + BATCH]])
        out[0].append(net(batch.images, net.token_ids(batch.texts)).numpy())
        out[1].append(batch.truths.numpy())
        out[2].append(batch.relations.numpy())
    return tuple(np.concatenate(x) for x in out)


def per_relation(logits: np.ndarray, truths: np.ndarray, relations: np.ndarray) -> dict:
    table = {"all": {"auc": roc_auc(logits, truths), "clauses": len(truths)}}
    for i, name in enumerate(RELATION_NAMES):
        on = relations == i
        table[name] = {"auc": roc_auc(logits[on], truths[on]), "clauses": int(on.sum())}
    return table


def evaluate(
    net: AgreementNet, data_dir: str | Path, predicted: str | Path | None = None, progress: bool = True
) -> dict:
    data = Dataset(data_dir)
    true_states = ClauseData(data, "test")
    result = {
        "true": per_relation(*scores(net, true_states, list(range(len(true_states))), progress=progress))
    }
    if predicted is not None:
        futures = PredictedStates(predicted, data)
        both = ClauseData(data, "test", futures)
        test = set(data.indices("test"))
        deep = [
            both.real + k
            for k in range(len(futures))
            if int(futures.step[k]) in PREDICTED_STEPS and int(futures.sequence[k]) in test
        ]
        if not deep:
            raise DataError(
                f"{predicted}: no predicted states of the test split (afford data predict --split test)"
            )
        result["predicted"] = per_relation(*scores(net, both, deep, progress=progress))
    return result


def format_table(result: dict) -> str:
    cols = [c for c in ("true", "predicted") if c in result]
    lines = [f"{'ROC AUC (clauses)':<22}" + "".join(f"{c + ' states':>22}" for c in cols)]
    for name in result["true"]:
        cells = []
        for c in cols:
            r = result[c][name]
            auc = "-" if np.isnan(r["auc"]) else f"{r['auc']:.3f}"
            cell = f"{auc} ({r['clauses']})"
            cells.append(f"{cell:>22}")
        lines.append(f"{name:<22}" + "".join(cells))
    return "\n".join(lines)
