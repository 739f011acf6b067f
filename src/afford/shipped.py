"""The nets a planner or an evaluation uses: one bundle, from one weights folder.

A weights folder holds the nets in the package's own layout (`afford weights export` writes
each file there): recognition.safetensors, prediction.safetensors, agreement.safetensors (goals
in words), and the object world model's objects/perception.safetensors and
objects/dynamics.safetensors. A folder of training runs (recognition/ and prediction/, each
with best.safetensors) serves for the first two. `Nets` loads each net on first use, so a
planner loads only what it needs and a closed loop, which builds its world model every round,
loads nothing twice. A net the folder lacks is a one-line
error naming the file when it is first needed, never a net taken from elsewhere.
"""

from __future__ import annotations

from functools import cached_property
from pathlib import Path

from afford.errors import UserError
from afford.training.checkpoint import BEST

WEIGHTS = Path(__file__).resolve().parent / "weights"  # shipped with the package
RECOGNITION_FILE = "recognition.safetensors"
PREDICTION_FILE = "prediction.safetensors"
AGREEMENT_FILE = "agreement.safetensors"  # goals in words (words/)
OBJECTS_DIR = "objects"  # the object world model's nets (afford.objects)
PERCEPTION_FILE = "perception.safetensors"  # in OBJECTS_DIR: E over objects
DYNAMICS_FILE = "dynamics.safetensors"  # in OBJECTS_DIR: P^a over objects
OBJECTS = WEIGHTS / OBJECTS_DIR
# A prediction net trained on continuous turns (paper V) for `--optimise-turns`, planned with
# the shipped recognition net: shipped apart because training on them cost the main net
# quarter-turn tasks.
CONTINUOUS_PREDICTION = WEIGHTS / "continuous" / PREDICTION_FILE

# The nets of a bundle, by the attribute that holds each (`Planner.needs` names them so).
KINDS = ("recognizer", "predictor", "perception", "dynamics", "agreement")


def kind_of(file: str) -> str | None:
    """The kind of net a file of the weights layout holds (None: no file of the layout)."""
    parts = Path(file).parts
    if parts == (RECOGNITION_FILE,):
        return "recognition"
    if parts == (AGREEMENT_FILE,):
        return "agreement"
    if parts in ((OBJECTS_DIR, PERCEPTION_FILE), (OBJECTS_DIR, DYNAMICS_FILE)):
        return Path(parts[1]).stem
    if parts[-1] == PREDICTION_FILE and len(parts) <= 2 and parts[0] != OBJECTS_DIR:
        return "prediction"  # the folder's own, or one shipped apart (continuous/)
    return None


class NetsError(UserError):
    """A weights folder without a net that is asked for; the message names the file."""


def agreement_net(path: str | Path):
    """The agreement model of goal sentences in a checkpoint or weights file."""
    from afford.training.checkpoint import load_net_from_checkpoint
    from afford.words.config import AgreementConfig
    from afford.words.model import AgreementNet

    return load_net_from_checkpoint(path, "agreement", AgreementConfig, AgreementNet)[0]


class Nets:
    """The nets of one weights folder (default: the package's), each loaded on first use.

    `prediction`: a prediction net's file used in place of the folder's (`--optimise-turns`
    plans with the continuous-turn net and the folder's other nets). Nets given by name
    (`recognizer=`, `predictor=`, ...) are used as they are: a test's or a benchmark's own.
    The object world model's renderer and the perceived-sim planner's second simulator are
    made once per bundle too, for the same reason as its nets.
    """

    def __init__(self, folder: str | Path | None = None, prediction: str | Path | None = None, **given):
        if unknown := set(given) - set(KINDS):
            raise TypeError(f"Nets: no net called {', '.join(sorted(unknown))}")
        self.folder = Path(folder) if folder is not None else WEIGHTS
        self.prediction_file = Path(prediction) if prediction is not None else None
        self.__dict__.update(given)  # a given net stands where its cached_property would load one

    def __repr__(self) -> str:
        return f"Nets({str(self.folder)!r})"

    def path(self, *names: str, run: str | None = None) -> Path:
        """A net's file in the folder (`names` joined under it), or its training run's
        best.safetensors (`run`: the run's folder name); NetsError where neither is there."""
        flat = self.folder.joinpath(*names)
        if flat.is_file():
            return flat
        if run is not None and (self.folder / run / BEST).is_file():
            return self.folder / run / BEST
        where = f"{'/'.join(names)}" + (f" (or a {run}/ run with {BEST})" if run else "")
        raise NetsError(
            f"{self.folder}: no {where}; a weights folder holds the nets in the package's layout "
            f"(`afford weights export`), e.g. copied from {WEIGHTS}"
        )

    def check(self, kinds) -> None:
        """Load the nets named (KINDS) now: a folder that lacks one says so before any planning."""
        for kind in kinds:
            getattr(self, kind)

    @cached_property
    def recognizer(self):
        from afford.recognition.infer import load_recognizer

        return load_recognizer(self.path(RECOGNITION_FILE, run="recognition"))

    @cached_property
    def predictor(self):
        from afford.prediction.evaluate import load_net

        path = self.prediction_file or self.path(PREDICTION_FILE, run="prediction")
        if not path.is_file():
            raise NetsError(f"{path}: no such prediction net")
        return load_net(path)[0]

    @cached_property
    def perception(self):
        from afford.objects.perception_train import load_perception

        return load_perception(self.path(OBJECTS_DIR, PERCEPTION_FILE))

    @cached_property
    def dynamics(self):
        from afford.objects.train import load_dynamics

        return load_dynamics(self.path(OBJECTS_DIR, DYNAMICS_FILE))

    @cached_property
    def agreement(self):
        return agreement_net(self.path(AGREEMENT_FILE))

    @cached_property
    def drawer(self):
        """The object world model's D: the simulator's renderer, drawing objects where they lie."""
        from afford.objects.draw import Drawer

        return Drawer()

    @cached_property
    def simulator(self):
        """A second simulator, where the perceived-sim planner builds the scenes it searches."""
        from afford.sim.scene import Scene

        return Scene()
