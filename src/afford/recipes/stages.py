"""Every stage of the shipped weights' recipes: one `afford` command each, in the order they run.

A stage is a dataset made (`afford generate`, `afford data predict`), a training run, a
calibration (`afford eval`, which writes a cut-off or a head's scaling into the run) or an
export (`afford weights export`). Its minutes are those measured on 2 cores (None: not measured);
its note says how they were measured where not by the run that made the shipped file, how that
run differed from the command here, or what is not known of it.
"""

from __future__ import annotations

import shlex
from dataclasses import dataclass

KINDS = ("data", "train", "calibrate", "export")
# Where `afford weights make` puts what it makes, relative to the folder it runs in.
MADE = "runs/made-weights"


@dataclass(frozen=True)
class Stage:
    name: str  # unique; also its stamp's file name
    kind: str  # one of KINDS
    command: str  # one `afford` command line, run in the repository root
    minutes: float | None  # on 2 cores, as measured; None: never measured
    note: str = ""  # how the first run differed, or what is not known of it

    @property
    def argv(self) -> list[str]:
        return shlex.split(self.command)

    def record(self) -> dict:
        return {
            "name": self.name,
            "kind": self.kind,
            "command": self.command,
            "minutes": self.minutes,
            "note": self.note,
        }


def _stage(name: str, kind: str, command: str, minutes: float | None, note: str = "") -> Stage:
    return Stage(name, kind, " ".join(command.split()), minutes, " ".join(note.split()))


_PREDICT_FIRST = (
    "the command named no --prediction, so the states came from the prediction net shipped then: "
    "the one-outcome net of runs/prediction"
)
_TIMED = "timed with the shipped file as the run's best checkpoint (the same net, so the same work)"
FOOT_MINUTES, CAL_MINUTES = 34, 0.37  # the footed recognition stages, as measured

# Every stage, in the order `afford weights make` runs them: each after the stages it reads.
STAGES: tuple[Stage, ...] = (
    _stage(
        "data-cpu",
        "data",
        "afford generate --out data/cpu --sequences 10000 --seed 0 --workers 2",
        14,
        "the default dataset: 34,888 executions, val and test 188 sequences each; 14 min as recorded "
        "when it was made again whole, 45 min or more on a machine making 10-13 executions a second",
    ),
    _stage(
        "data-part",
        "data",
        "afford generate --out data/part --sequences 5200 --seed 0 --splits-of 10000",
        6.8,
        "the first 5,200 sequences of data/cpu with its val and test splits (4,824 training "
        "sequences); first made as a view of data/cpu's first 208 shards with a manifest written by "
        "hand; the minutes are this command's",
    ),
    _stage(
        "data-effects",
        "data",
        "afford generate --out data/effects --sequences 1500 --seed 11 --actions effects --workers 2",
        15.5,
        "side effects sought: 5,307 executions, 39% of them with a side effect; timed while sharing "
        "the machine",
    ),
    _stage(
        "data-cont",
        "data",
        "afford generate --out data/cont --sequences 6000 --seed 2 --turn-angles continuous --workers 2",
        7,
        "turns by any angle: 20,920 executions",
    ),
    _stage(
        "train-prediction-one-outcome",
        "train",
        "afford train prediction --data data/cpu --preset cpu --out runs/prediction",
        72,
        "the one-outcome net, shipped before the two-outcome one; its rollouts are the predicted "
        "states the recognition and agreement models train on",
    ),
    _stage(
        "predict-recognition-states",
        "data",
        "afford data predict data/cpu --out data/predicted/train-3000.npz --sequences 3000 "
        "--prediction runs/prediction/best.safetensors",
        7,
        f"10,493 states; {_PREDICT_FIRST}; 7 min while sharing the machine",
    ),
    _stage(
        "predict-agreement-states",
        "data",
        "afford data predict data/part --split train --sequences 1500 --out data/predicted/words-train.npz "
        "--prediction runs/prediction/best.safetensors",
        0.56,
        f"{_PREDICT_FIRST}; timed with a one-outcome net of the same preset trained one batch "
        "(the same work)",
    ),
    _stage(
        "train-recognition-10k",
        "train",
        "afford train recognition --data data/cpu --preset cpu --set steps=10000 --out runs/recognition-10k",
        75,
        "10,000 batches of 32 from scratch",
    ),
    _stage(
        "train-recognition",
        "train",
        "afford train recognition --data data/cpu --preset cpu --init runs/recognition-10k/last.safetensors "
        "--predicted data/predicted/train-3000.npz --set steps=4000 --set lr=5e-4 --set warmup=100 "
        "--set predicted_fraction=0.25 --out runs/rec-10k-ft",
        37,
        "4,000 batches more at a lower rate, a quarter of the draws predicted states",
    ),
    _stage(
        "data-cpu-4k",
        "data",
        "afford generate --out data/cpu-4k --sequences 4000 --seed 0 --splits-of 10000 --workers 2",
        17,
        "the first 4,000 sequences of data/cpu with its val and test splits; 17 min while sharing the "
        "machine; first made with each support's post reaching the table beside its foot (the same "
        "images; contacts with the table that the post standing on its foot leaves to the foot alone)",
    ),
    _stage(
        "train-recognition-foot",
        "train",
        "afford train recognition --data data/cpu-4k --preset cpu --init runs/rec-10k-ft/best.safetensors "
        "--set steps=1000 --set lr=5e-4 --set warmup=50 --out runs/rec-foot",
        FOOT_MINUTES,
        "1,000 batches on the world whose supports stand on a foot the camera sees; --init named the "
        "file shipped at commit 5f2c4df, which the stages before this one made on the world of posts "
        "without feet (made again, they run on the footed world); timed while sharing the machine",
    ),
    _stage(
        "calibrate-recognition",
        "calibrate",
        "afford eval recognition --run runs/rec-foot --data data/cpu-4k",
        CAL_MINUTES,
        "the cut-off picked on val (the best recall within 0.15 spurious detections per image), in "
        "RUN/threshold.json",
    ),
    _stage(
        "export-recognition",
        "export",
        f"afford weights export recognition.safetensors --run runs/rec-foot --out {MADE}",
        0.04,
        "float32 with its cut-off",
    ),
    _stage(
        "train-prediction",
        "train",
        "afford train prediction --data data/cpu --more-data data/effects --preset cpu-two-outcome "
        "--out runs/two-outcome",
        152,
        "4,200 batches; its first 3,350 beside other work (about 27 a minute), stopped there and "
        "resumed from its batch-3,250 checkpoint on an idle machine (about 36 a minute)",
    ),
    _stage(
        "calibrate-prediction",
        "calibrate",
        "afford eval prediction --run runs/two-outcome --data data/cpu --no-futures",
        0.95,
        "the choice head's Platt scaling fitted on val, one for all action types and one per type, "
        "in RUN/calibration.json",
    ),
    _stage(
        "export-prediction",
        "export",
        f"afford weights export prediction.safetensors --run runs/two-outcome --out {MADE}",
        0.03,
        "float16 with the calibrated head",
    ),
    _stage(
        "train-continuous-mixed",
        "train",
        "afford train prediction --data data/cont --more-data data/effects --preset cpu-two-outcome "
        "--init runs/two-outcome/best.safetensors --set turn_fraction=0.5 --set effect_fraction=0.3 "
        "--set lr=3e-4 --set warmup=50 --steps 1400 --out runs/cont",
        31,
        "the prediction net fine-tuned on continuous turns with the side effects joined; first run "
        "with --preset cpu and the prediction net's --set fields, from the prediction net of the "
        "world of posts alone (runs/scratch-clip, shipped at commit 4fba93f)",
    ),
    _stage(
        "train-continuous",
        "train",
        "afford train prediction --data data/cont --preset cpu-two-outcome --init runs/cont/best.safetensors "
        "--set turn_fraction=0.7 --set effect_fraction=0 --set lr=5e-4 --set warmup=50 --steps 1400 "
        "--out runs/turns",
        31,
        "data/cont alone, 70% of the runs holding a turn; first run with --preset cpu and the "
        "prediction net's --set fields but effect_fraction, which the file's config records as 0",
    ),
    _stage(
        "calibrate-continuous",
        "calibrate",
        "afford eval prediction --run runs/turns --data data/part --no-futures",
        0.68,
        "first fitted one for all action types only (sigmoid(0.85 z - 0.44)), before the fit per type "
        f"existed: made again, the file also carries a scaling per type; {_TIMED}",
    ),
    _stage(
        "export-continuous",
        "export",
        f"afford weights export continuous/prediction.safetensors --run runs/turns --out {MADE}",
        0.03,
        f"first written by `afford export`, whose recognition net was not kept in continuous/; {_TIMED}",
    ),
    _stage(
        "train-agreement-8k",
        "train",
        "afford train goals --data data/part --predicted data/predicted/words-train.npz --out runs/attend8k",
        38.8,
        "the cpu preset: 8,000 batches of 40 draws",
    ),
    _stage(
        "train-agreement-11k",
        "train",
        "afford train goals --data data/part --predicted data/predicted/words-train.npz "
        "--init runs/attend8k/best.safetensors --steps 3000 --set lr=1e-3 --set warmup=50 "
        "--out runs/attend11k",
        14,
    ),
    _stage(
        "train-agreement-17k",
        "train",
        "afford train goals --data data/part --predicted data/predicted/words-train.npz "
        "--init runs/attend11k/best.safetensors --steps 6000 --set lr=1e-3 --set warmup=50 "
        "--out runs/attend17k",
        33,
        "33 min with a pause",
    ),
    _stage(
        "train-agreement-ground",
        "train",
        "afford train goals --data data/part --predicted data/predicted/words-train.npz --preset cpu "
        "--init runs/attend17k/best.safetensors --set loss_ground=1.0 --set lr=1e-3 --set warmup=50 "
        "--steps 3000 --out runs/ground",
        12.4,
        "the attention maps taught where the clause's objects are",
    ),
    _stage(
        "train-agreement",
        "train",
        "afford train goals --data data/part --predicted data/predicted/words-train.npz --preset cpu "
        "--init runs/ground/best.safetensors --set loss_ground=1.0 --set geometry=true --set lr=1e-3 "
        "--set warmup=50 --steps 2000 --out runs/geom",
        8,
        "the geometric read of the maps' centres",
    ),
    _stage(
        "export-agreement",
        "export",
        f"afford weights export agreement.safetensors --run runs/geom --out {MADE}",
        0.04,
        f"float16; how the file was first written is not recorded; {_TIMED}",
    ),
    # The object world model (afford.objects): its datasets have seeds of their own.
    _stage(
        "data-poses",
        "data",
        "afford generate --out data/poses --sequences 6000 --seed 100 --poses-only --workers 2",
        7,
        "poses, held objects and the arm's path, no images: about 20,900 executions",
    ),
    _stage(
        "data-poses-102",
        "data",
        "afford generate --out data/poses-102 --sequences 6000 --seed 102 --poses-only --workers 2",
        7,
        "as data/poses, another seed: the dynamics learn from three such sets",
    ),
    _stage(
        "data-poses-103",
        "data",
        "afford generate --out data/poses-103 --sequences 6000 --seed 103 --poses-only --workers 2",
        7,
        "as data/poses, a third seed",
    ),
    _stage(
        "data-poses-effects",
        "data",
        "afford generate --out data/poses-effects --sequences 1200 --seed 101 --poses-only --actions effects "
        "--workers 2",
        8,
        "poses of executions that seek side effects: about 4,200 executions",
    ),
    _stage(
        "data-objects-train",
        "data",
        "afford generate --out data/objects-train --sequences 2000 --seed 201 --masks --workers 2",
        10,
        "images with their instance masks: what perception learns from",
    ),
    _stage(
        "train-dynamics",
        "train",
        "afford train dynamics --data data/poses --more-data data/poses-102 --more-data data/poses-103 "
        "--more-data data/poses-effects --out runs/dynamics",
        17,
        "the cpu preset: 16,000 batches of 256 executions, from about 64,400; then the outcome "
        "temperature fitted on the val splits (RUN/calibration.json, seconds)",
    ),
    _stage(
        "export-dynamics",
        "export",
        f"afford weights export objects/dynamics.safetensors --run runs/dynamics --out {MADE}",
        0.03,
        "float16, with the outcome temperature in its config; timed as made again from this recipe",
    ),
    _stage(
        "train-perception",
        "train",
        "afford train perception --data data/objects-train --out runs/perception",
        48,
        "the cpu preset: 8,000 batches of 16 images",
    ),
    _stage(
        "export-perception",
        "export",
        f"afford weights export objects/perception.safetensors --run runs/perception --out {MADE}",
        0.03,
        "float16; timed as made again from this recipe",
    ),
)

BY_NAME: dict[str, Stage] = {s.name: s for s in STAGES}
