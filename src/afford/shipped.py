"""The shipped nets: where a weights folder keeps them, and how they load.

Package-level, below the planners and the evaluations that use them: `afford plan`, `afford
eval`, the benchmarks and the tests all load the nets through `load_learned`.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from afford.prediction.ensemble import check_members, member_paths
from afford.prediction.evaluate import load_net as load_prediction
from afford.prediction.model import PredictionNet
from afford.recognition.infer import Recognizer, load_net, read_threshold
from afford.training.checkpoint import BEST

WEIGHTS = Path(__file__).resolve().parent / "weights"  # shipped with the package
RECOGNITION_FILE = "recognition.safetensors"
PREDICTION_FILE = "prediction.safetensors"
AGREEMENT_FILE = "agreement.safetensors"  # goal sentences (words/), beside the two nets
# A prediction net trained on continuous turns (paper V) for `--optimise-turns`, with the shipped
# recognition net: shipped apart because training on them cost the main net quarter-turn tasks.
CONTINUOUS = WEIGHTS / "continuous"
# The object world model's nets (afford.objects): perception (E) and dynamics (P^a).
OBJECTS = WEIGHTS / "objects"
PERCEPTION_FILE = "perception.safetensors"
DYNAMICS_FILE = "dynamics.safetensors"


def _object_net(weights: str | Path | None, name: str, fallback: bool) -> Path:
    """A net's file in a weights folder; with fallback, the shipped one when the folder lacks it."""
    path = Path(weights or OBJECTS) / name
    return OBJECTS / name if fallback and not path.is_file() else path


def load_object_perception(weights: str | Path | None = None, fallback: bool = False):
    """The object perception net from a weights folder (default: the shipped one)."""
    from afford.objects.perception_train import load_perception

    return load_perception(_object_net(weights, PERCEPTION_FILE, fallback))


def load_object_dynamics(weights: str | Path | None = None, fallback: bool = False):
    """The object dynamics net (P^a over objects) from a weights folder (default: the shipped one)."""
    from afford.objects.train import load_dynamics

    return load_dynamics(_object_net(weights, DYNAMICS_FILE, fallback))


def find_weights(weights: str | Path | None = None) -> tuple[Path, Path]:
    """The recognition and prediction checkpoints in a folder (default: the shipped ones).

    A folder may also be a pair of training runs: recognition/ and prediction/ inside it, each
    with best.safetensors.
    """
    root = Path(weights) if weights else WEIGHTS
    # A folder inside the shipped one may hold a prediction net alone, and shares the recognition net.
    shared = WEIGHTS if root.resolve().parent == WEIGHTS and not (root / RECOGNITION_FILE).exists() else root
    flat = (shared / RECOGNITION_FILE, root / PREDICTION_FILE)
    runs = (root / "recognition" / BEST, root / "prediction" / BEST)
    for rec, pred in (flat, runs):
        if rec.is_file() and pred.is_file():
            return rec, pred
    raise FileNotFoundError(
        f"{root}: no weights ({RECOGNITION_FILE} and {PREDICTION_FILE}, or recognition/ and "
        "prediction/ runs with best.safetensors)"
    )


@dataclass
class LearnedNets:
    """The trained nets of a weights folder."""

    recognizer: Recognizer  # with its tuned cut-off
    predictor: PredictionNet
    # The prediction nets of the ensemble planner (prediction/ensemble.py): the predictor
    # first, then the folder's ensemble/ members; just the predictor when it has none.
    members: tuple[PredictionNet, ...] = ()


def load_learned(weights: str | Path | None = None) -> LearnedNets:
    """The recognizer, the prediction net and the ensemble's members from a weights folder
    (default: the shipped one)."""
    rec_path, pred_path = find_weights(weights)
    net, config, meta = load_net(rec_path)
    threshold = meta.get("extra", {}).get("threshold")  # set by `afford export`
    if threshold is None:
        threshold = read_threshold(rec_path.parent)  # tuned by `afford eval recognition`
    predictor, _ = load_prediction(pred_path)
    members = [predictor] + [load_prediction(p)[0].eval() for p in member_paths(pred_path.parent)]
    check_members(members)
    return LearnedNets(Recognizer(net, config, threshold), predictor, tuple(members))
