"""Prediction pathway configuration (paper II.C, III.C), with its presets."""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

from afford.sim.affordances import TYPES
from afford.sim.camera import SIZE
from afford.training.fields import with_fields

CHANGED = 0.02  # ours: a ground-truth pixel changed when a channel moved by more than this


@dataclass(frozen=True)
class ModelConfig:
    """The net's shape: E, P^a per affordance type, D (paper II.C)."""

    # "dense": the paper's vector latent (dense.py, the `paper` preset); "spatial": a latent
    # grid (spatial.py), the shipped nets'.
    architecture: str = "spatial"
    channels: int = 4  # RGBD
    # --- dense: E and D (D mirrors E).
    conv_channels: int = 8  # 2 convolutions, 3x3, stride 2: 128x128 -> 32x32x8 = 8192
    dense: tuple[int, ...] = (512,)  # dense layers between the 8192 conv features and the latent
    latent: int = 128
    image_size: int = SIZE  # the camera's
    p_layers: int = 10  # dense P^a: tanh layers, each 2 x latent wide (state half | memory half)
    # --- spatial: E's strided convolutions set the grid (128 / 2^3 = 16); P^a residual blocks
    # on it; D's upsampling stages back to 64 x 64, then a stage on 2x2 pixel blocks that also
    # sees the current image.
    activation: str = "gelu"
    encoder_channels: tuple[int, ...] = (32, 64, 64)
    latent_channels: int = 32
    memory_channels: int = 16
    p_channels: int = 64
    p_blocks: int = 3
    blob_sigma: float = 0.8  # the action blob's width, in grid cells
    decoder_channels: tuple[int, ...] = (64, 32, 16)  # at 16, 32 and 64 px
    full_channels: int = 24  # the last stage, on 2x2 pixel blocks at 64 px
    # --- both
    types: tuple[str, ...] = TYPES  # one P^a per affordance type
    pixel_input: bool = True  # the affordance pixel's RGBD in the action vector (Table 2 ablation)
    # Action vector normalisation: (position - centre) / scale, so its values are order 1.
    position_centre: tuple[float, float, float] = (0.0, 0.27, 0.05)
    position_scale: tuple[float, float, float] = (0.2, 0.2, 0.1)

    @property
    def latent_size(self) -> int:
        return self.image_size // 2 ** len(self.encoder_channels)

    @property
    def conv_size(self) -> int:
        return self.image_size // 4

    @property
    def conv_features(self) -> int:
        return self.conv_channels * self.conv_size**2

    @property
    def action_size(self) -> int:
        # x, y, z, angle (fraction of a turn), turn parameter (+-1, 0), the pixel's RGBD
        return 5 + self.channels


@dataclass(frozen=True)
class OutcomesConfig:
    """How many outcomes D draws per step, where they part, and the head that says which follows."""

    # 1: one image, as the paper; K > 1 (spatial only): K candidate images and a head that
    # scores them, trained winner-takes-all: the candidate nearest the truth takes the loss and
    # is carried to the next step, the head learns which one won. One image can only hedge
    # between "the ball stays" and "the ball falls" (a blur that matches neither); K can draw
    # both, sharp, and say which is likely.
    hypotheses: int = 2
    # Which candidate takes each step's loss: "winner", the one nearest the truth; "effect"
    # (K = 2), chosen by the step's label (data/effects.py): the first draws canonical steps,
    # the second steps with a side effect, and the head learns how likely a side effect is.
    hypotheses_by: str = "effect"
    # Where the candidates part (model.FORKS): "decoder", they share E, P^a and D but D's last
    # layer (one latent, K images drawn from it); "latent", each P^a's last block and output
    # layer are repeated per candidate, so each outcome has its own dc and D decodes each: the
    # latent itself forks, and the candidate carried on gives eq. (2) its dc.
    fork: str = "latent"
    # With hypotheses_by=effect, in use: the side-effect outcome is carried on where the head
    # gives it more than this probability (0.5: the likelier). A cut-off tuned on val, as the
    # recognition net's is: a second outcome drawn where none follows costs canonical plans.
    effect_threshold: float = 0.5
    # The head's side-effect logit (the second outcome's minus the first's) is read as
    # sigmoid(choice_scale * logit + choice_bias): Platt scaling fitted on val
    # (prediction/calibration.py). Training draws side-effect runs more often than they come
    # (sampling.effect_fraction), so the raw head overstates how often one follows; the planner
    # that weighs outcomes by their probability (planning/branches.py) needs them as they come.
    choice_scale: float = 1.0
    choice_bias: float = 0.0
    # The same fitted per action type (in sim.affordances.TYPES order; empty: the one above for
    # all). Side effects follow 3% of grasps, 16% of places and 46% of turns, and one scaling
    # left the head underconfident where places tip the block (benchmarks/place_outcomes.py).
    choice_scales: tuple[float, ...] = ()
    choice_biases: tuple[float, ...] = ()


@dataclass(frozen=True)
class LossConfig:
    """The loss per step (train.sequence_loss), each term's weight (0: off)."""

    # The weights' flat names (`--set loss_l1=1`): "l1" alone does not say it is a loss's.
    flat_names: ClassVar[dict[str, str]] = {
        k: f"loss_{k}" for k in ("mse", "l1", "mask", "values", "choice", "others")
    }

    # mse * squared error + l1 * absolute error (both summed over channels, mean over pixels)
    # + mask * squared error of eq. (3)'s mask against where the truth changed + values * D's
    # new values' absolute error there.
    mse: float = 1.0
    l1: float = 1.0
    mask: float = 0.1
    values: float = 0.1
    choice: float = 0.1  # K > 1: the choice head's cross-entropy against the winner
    others: float = 0.05  # K > 1: every candidate's absolute error, so that none stops learning


@dataclass(frozen=True)
class SamplingConfig:
    """Which training runs are drawn, and how each is augmented."""

    max_steps: int = 4  # executions per training run (1-4, random start)
    shift_px: int = 3
    mirror: bool = True
    angle_flip: bool = True
    position_noise: float = 0.002
    angle_noise: float = 1.0
    # The run's random stream (data order, augmentation): nets trained apart differ by it.
    seed: int = 0
    # Train on a resample, with replacement, of the training sequences drawn from `seed`: a
    # bootstrap, so that nets trained apart disagree where the data is thin.
    bootstrap: bool = False
    # The share of training runs drawn from sequences with a turn (0: as the data comes, about
    # a quarter with turns): more turn examples for P^turn, for continuous turn angles (paper V).
    turn_fraction: float = 0.0
    # The share of training runs drawn from sequences with a side effect (data/effects.py; 0: as
    # the data comes, about 4 in 10 sequences hold one somewhere). With turn_fraction too, each
    # share is a floor (a sequence may hold both) and the rest holds neither.
    effect_fraction: float = 0.5
    # The share drawn from sequences where a place had a side effect (the block tips, the object
    # placed falls or slides): a floor beside the two above. Places are the side effects the net
    # foresees worst, and its head is underconfident where a place at a block's end tips it
    # every time (benchmarks/place_outcomes.py); one place in six has one, so few runs show it.
    place_effect_fraction: float = 0.0


@dataclass(frozen=True)
class TrainingConfig:
    """The optimiser, its schedule, and the machine it runs on."""

    optimizer: str = "adam"  # "signsgd" as the paper, or "adam"
    lr: float = 1e-3
    batch_size: int = 32
    steps: int = 4200
    eval_every: int = 250
    log_every: int = 25
    schedule: str = "cosine"  # "plateau": the paper's halving; "cosine": warm-up, cosine decay
    patience: int = 5  # plateau: halve the lr after this many evaluations without improvement (paper)
    warmup: int = 200  # cosine: batches of linear warm-up
    # Gradients rescaled to at most this norm before each step (0: off). A from-scratch
    # two-outcome run (fork=latent) met one batch of loss 1.3e6 at step 300 (the choice head's
    # cross-entropy on an unbounded dc): the gradient filled Adam's second moments, and the net
    # learned at a fraction of its rate for the rest of the run (val error 3x the one-outcome run's).
    grad_clip: float = 1.0
    threads: int = 2
    loader_workers: int = 1  # background processes building batches (0: in the training thread)


@dataclass(frozen=True)
class PredictionConfig:
    """The EM*D net's config: its shape, outcomes, loss, training runs and schedule, each a
    record. `training.fields` gives each field a flat name too (`lr`, `hypotheses`, `loss_l1`), as
    `--set` and configs stored as one flat dict (the shipped files) write them. The defaults are
    the shipped prediction net's recipe (`cpu-two-outcome`)."""

    # Fields that shipped files store but this code does not vary: each with the one value it
    # runs (training/fields.from_dict refuses a stored config that asks for another).
    removed: ClassVar[dict[str, object]] = {
        "variance": False,
        "variance_scale": 1.0,
        "fork_blocks": 1,
        "choice_head": "pooled",
        "choice_channels": 32,
        "repair": False,
        "loss_effect": 0.0,
        "effect_region": "effects",
        "loss_coarse": 0.0,
        "coarse_px": 8,
        "loss_nll": 0.0,
        "nll_beta": 0.5,
        "bf16": False,
        "trained": "all",
    }

    model: ModelConfig = ModelConfig()
    outcomes: OutcomesConfig = OutcomesConfig()
    loss: LossConfig = LossConfig()
    sampling: SamplingConfig = SamplingConfig()
    training: TrainingConfig = TrainingConfig()


# Tests' nets: a few batches of 4, built in the training thread.
_TINY_SCHEDULE = {"batch_size": 4, "loader_workers": 0, "steps": 20, "eval_every": 10, "log_every": 5}

# One outcome per step, as the paper: the net the recognition and agreement models' predicted
# training states come from (afford/recipes/).
_CPU = with_fields(
    PredictionConfig(),
    hypotheses=1,
    hypotheses_by="winner",
    fork="decoder",
    effect_fraction=0.0,
    grad_clip=0.0,
)

# The paper's dense latent at CPU size: the paper's schedule and losses.
_DENSE = with_fields(
    _CPU,
    architecture="dense",
    loss_l1=0.0,
    loss_mask=0.0,
    loss_values=0.0,
    schedule="plateau",
    steps=3000,
)

PRESETS = {
    "cpu": _CPU,
    # The shipped prediction nets' recipe (afford/recipes/; with --more-data data/effects), the
    # defaults: two outcomes forked in the latent, the second drawing side effects, half the
    # runs holding one, and the gradient clipped, which a two-outcome run from scratch needs.
    "cpu-two-outcome": PredictionConfig(),
    "dense-cpu": _DENSE,
    # The paper's sizes (II.C; the authors' public configuration for the P modules) and schedule.
    "paper": with_fields(
        _DENSE,
        dense=(4096,),
        latent=128,
        optimizer="signsgd",
        lr=5e-5,
        steps=1_000_000,
        eval_every=10_000,
        log_every=500,
    ),
    "tiny": with_fields(
        _CPU,
        schedule="plateau",
        encoder_channels=(4, 8, 8),
        latent_channels=4,
        memory_channels=2,
        p_channels=8,
        p_blocks=1,
        decoder_channels=(8, 4, 4),
        full_channels=8,
        **_TINY_SCHEDULE,
    ),
    "tiny-dense": with_fields(
        _DENSE,
        conv_channels=2,
        dense=(16,),
        latent=8,
        p_layers=2,
        **_TINY_SCHEDULE,
    ),
}
