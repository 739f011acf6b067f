"""Agreement model configuration (words/model.py), with presets."""

from __future__ import annotations

from dataclasses import dataclass

from afford.sim.camera import SIZE


@dataclass(frozen=True)
class AgreementConfig:
    # Architecture: a strided convolution stem, then FiLM blocks conditioned on the clause.
    in_channels: int = 4  # RGBD
    image_size: int = SIZE
    stem: tuple[int, ...] = (24, 48, 64)  # channels at strides 2, 4, 8: a 16x16 grid on 128x128
    blocks: int = 3  # FiLM residual blocks on the grid
    width: int = 64  # the grid's channels in the blocks
    embed: int = 48  # word embedding
    text: int = 96  # the clause encoder's GRU state
    head: int = 128
    # The readout (model.READOUTS): "pool", the grid's max and mean beside the clause; "attend",
    # also two clause-chosen attention maps over the grid (what the clause is about, and what
    # it is compared with), each read as its features and its centre's coordinates, so "left
    # of" compares two places instead of hoping a pooled channel kept them.
    readout: str = "pool"
    # Weight of the stem's object maps (model.AgreementNet.objects): per grid cell, whether a
    # cup, a ball, a support or the block is centred there (true poses, through the camera),
    # so that the stem learns to see the objects and where they are, whatever the clause.
    loss_objects: float = 0.0
    # Weight of the "attend" readout's grounding: its first map taught to fall on the clause's
    # subject and its second on the other object (data.place_maps: true poses through the
    # camera; cross-entropy against a bump), so the centres the head compares are the objects
    # the clause names, not whatever the clause alone lets the maps settle on.
    loss_ground: float = 0.0
    # With readout=attend: the clause also weighs, linearly, the two maps' centres and their
    # offset (in cells), added to the head's logit (model.GEOMETRY). "Left of" is then a sign
    # on a column difference that the clause chooses, not a product of text and place that the
    # head's hidden layer must discover among some 360 features.
    geometry: bool = False
    # The words the model reads, in token-id order: filled from words/sentences.vocabulary()
    # when training starts, and kept with the weights.
    vocabulary: tuple[str, ...] = ()
    # Training: clauses sampled afresh for every state drawn, half of them true.
    batch_size: int = 40  # draws; each gives its clause on a second state too, where one is found
    lr: float = 2e-3
    weight_decay: float = 1e-4
    steps: int = 3000
    warmup: int = 150
    eval_every: int = 250
    log_every: int = 25
    shift_px: int = 2  # no mirroring: it would swap left and right
    # With `afford train goals --predicted FILE`: this share of the draws are predicted states,
    # whose clauses are judged on the true state they predict.
    predicted_fraction: float = 0.5
    threads: int = 2
    seed: int = 0

    def __post_init__(self):
        # Both options work on the "attend" readout's two maps; a config asking for them without
        # it is refused wherever it is built (a preset, --set, a checkpoint).
        if self.loss_ground and self.readout != "attend":
            raise ValueError('loss_ground teaches the "attend" readout\'s maps: set readout=attend')
        if self.geometry and self.readout != "attend":
            raise ValueError('geometry weighs the "attend" readout\'s centres: set readout=attend')

    @property
    def grid(self) -> int:
        """The stem's grid size: one cell per 2^len(stem) pixels."""
        return self.image_size // 2 ** len(self.stem)


PRESETS = {
    # The shipped model's first stage (39 min on 2 cores); it was then trained on from there, the
    # last two stages with --set loss_ground=1.0 and then also --set geometry=true
    # (docs/beyond-the-paper.md, goals in words, has each stage's command and figures).
    "cpu": AgreementConfig(readout="attend", loss_objects=1.0, steps=8000),
    # The design before: pooled readout, no object maps (for comparison).
    "cpu-pool": AgreementConfig(),
    "tiny": AgreementConfig(
        stem=(4, 8, 8),
        blocks=1,
        width=8,
        embed=8,
        text=8,
        head=8,
        batch_size=8,
        steps=20,
        eval_every=10,
        log_every=5,
        warmup=5,
    ),
}
