"""The recipe of every shipped weights file: which stages (stages.py) make it, and what is known.

One entry per file under `weights/`.
"""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class Recipe:
    file: str  # relative to the weights folder, e.g. "continuous/prediction.safetensors"
    net: str  # what the file holds, in a line
    stages: tuple[str, ...]  # names in STAGES, in the order they run
    trained: str  # the training stage whose run the file is exported from
    commit: str  # the commit that shipped the file as it is
    unknown: tuple[str, ...] = ()  # details of the first making that are not on record


FOOT_COMMIT = "9f1c7cf"  # the commit that ships the recognition net of the footed world
FOOT_PREDICTION_COMMIT = "5f8938e"  # the commit that ships the prediction net of the footed world
_BUILDS = "the MuJoCo and torch builds the data and training first ran on (constraints.txt pins them now)"

# One entry per shipped file, by its path under weights/.
RECIPES: dict[str, Recipe] = {
    r.file: r
    for r in (
        Recipe(
            "recognition.safetensors",
            "the affordance recognition net (paper II.B), cpu preset, with its cut-off",
            (
                "data-cpu",
                "train-prediction-one-outcome",
                "predict-recognition-states",
                "train-recognition-10k",
                "train-recognition",
                "data-cpu-4k",
                "train-recognition-foot",
                "calibrate-recognition",
                "export-recognition",
            ),
            trained="train-recognition-foot",
            commit=FOOT_COMMIT,
            unknown=(_BUILDS,),
        ),
        Recipe(
            "prediction.safetensors",
            "the EM*D prediction net (paper II.C), cpu preset with two outcomes forked in the latent",
            (
                "data-cpu",
                "data-effects",
                "train-prediction",
                "calibrate-prediction",
                "export-prediction",
            ),
            trained="train-prediction",
            commit=FOOT_PREDICTION_COMMIT,
        ),
        Recipe(
            "continuous/prediction.safetensors",
            "the continuous-turn prediction net (paper V, --optimise-turns): the prediction net "
            "fine-tuned in two stages on turns by any angle",
            (
                "data-cpu",
                "data-part",
                "data-effects",
                "data-cont",
                "train-prediction",
                "train-continuous-mixed",
                "train-continuous",
                "calibrate-continuous",
                "export-continuous",
            ),
            trained="train-continuous",
            commit="4aab0f6",
            unknown=(_BUILDS,),
        ),
        Recipe(
            "agreement.safetensors",
            "the agreement model of goal sentences (paper V), cpu preset trained, then trained on in "
            "four more stages",
            (
                "data-cpu",
                "data-part",
                "train-prediction-one-outcome",
                "predict-agreement-states",
                "train-agreement-8k",
                "train-agreement-11k",
                "train-agreement-17k",
                "train-agreement-ground",
                "train-agreement",
                "export-agreement",
            ),
            trained="train-agreement",
            commit="67d4a3f",
            unknown=(
                _BUILDS,
                "whether data/predicted/words-train.npz was made again between the stages, with a "
                "later prediction net",
            ),
        ),
        Recipe(
            "objects/dynamics.safetensors",
            "the object world model's dynamics: an interaction network per affordance type over the "
            "objects, K outcomes with their probabilities",
            (
                "data-poses",
                "data-poses-102",
                "data-poses-103",
                "data-poses-effects",
                "train-dynamics",
                "export-dynamics",
            ),
            trained="train-dynamics",
            commit="91bd79a",
        ),
        Recipe(
            "objects/perception.safetensors",
            "the object world model's perception: the objects in one RGBD state image",
            ("data-objects-train", "train-perception", "export-perception"),
            trained="train-perception",
            commit="081328c",
        ),
    )
}
