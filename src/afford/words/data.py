"""Training data for the agreement model: a state's image and a clause sampled about it.

Every state of a split (and, with a file of predicted states, every predicted state, judged by
the true state it predicts) is drawn with a clause that is true or false with even odds, sampled
afresh at each draw from the state's facts (`words/sentences.py`), so the model never sees one
fixed set of sentences.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import torch
from torch.utils.data import Dataset as TorchDataset

from afford.data.augment import NO_AUGMENT, AugmentConfig, augment
from afford.data.format import Dataset
from afford.data.predicted import PredictedStates
from afford.images import to_chw
from afford.sim import camera
from afford.sim.constants import KINDS
from afford.words.facts import RELATION_NAMES, Fact, State
from afford.words.sentences import Clause, SentenceError, names, parse, sample_clause, write

RELATION_IDS = {r: i for i, r in enumerate(RELATION_NAMES)}
OBJECT_SIGMA = 0.7  # object maps' bump width, in grid cells


def sequence_state(seq, t: int) -> State:
    """State t of a format.Sequence, its hidden objects read from its image."""
    return State.in_sequence(seq.poses, seq.held, seq.slots, t, seq.image(t))


def _bump(state: State, k: int, size: int, sigma: float) -> np.ndarray | None:
    """(size, size): a Gaussian (sigma in cells) where object slot k is centred through the
    camera; None when the image does not show it."""
    if not state.present(k) or k in state.hidden:
        return None
    col, row = camera.world_to_pixel(state.poses[k][None, :3].astype(float))[0] * (size / camera.SIZE)
    cells = np.arange(size) + 0.5
    return np.exp(-0.5 * (((cells[None, :] - col) ** 2 + (cells[:, None] - row) ** 2) / sigma**2))


def object_maps(state: State, size: int, sigma: float = OBJECT_SIGMA) -> np.ndarray:
    """(len(KINDS), size, size) in [0, 1]: a Gaussian (sigma in cells) where each object the
    image shows is centred, through the camera, one channel per kind; what the agreement
    model's stem is taught to see (config.loss_objects)."""
    maps = np.zeros((len(KINDS), size, size), np.float32)
    for k in range(len(state.slots)):
        bump = _bump(state, k, size, sigma)
        if bump is not None:
            channel = KINDS.index(state.kind(k))
            maps[channel] = np.maximum(maps[channel], bump)
    return maps


def place_maps(state: State, fact: Fact, size: int, sigma: float = OBJECT_SIGMA) -> np.ndarray:
    """(2, size, size): where the clause's subject and its other object are (each a bump that
    sums to 1), zeros for one the image does not show or a word ("table", "left"); what the
    "attend" readout's two maps are taught to find (config.loss_ground)."""
    maps = np.zeros((2, size, size), np.float32)
    for m, k in enumerate((fact.subject, fact.other)):
        bump = _bump(state, k, size, sigma) if isinstance(k, int | np.integer) else None
        if bump is not None:
            maps[m] = bump / bump.sum()
    return maps


def draw_clause(state: State, rng: np.random.Generator) -> tuple[str, bool, Fact] | None:
    """(text, truth, fact) of a clause about `state`, true with even odds; None when the
    state affords no clause (no object it can name)."""
    called = names(state)
    truth = bool(rng.random() < 0.5)
    for want in (truth, not truth):
        clause: Clause | None = sample_clause(state, want, rng, called)
        if clause is not None:
            return write(clause, called, rng), want, clause.fact
    return None


class ClauseData(TorchDataset):
    """(image (4, H, W), clause text, truth, relation id) per draw: true states of a split, then
    the predicted states of `predicted` (a PredictedStates) if given."""

    def __init__(
        self,
        data: Dataset,
        split: str,
        predicted: PredictedStates | None = None,
        augment_config: AugmentConfig = NO_AUGMENT,
        seed: int = 0,
        grid: int = 16,
    ):
        self.data = data
        self.items = [(i, t) for i in data.indices(split) for t in range(data.sequence(i).length + 1)]
        self.real = len(self.items)
        self.predicted = predicted
        if predicted is not None:
            self.items += [(int(i), int(t)) for i, t in zip(predicted.sequence, predicted.step, strict=True)]
        self.config = augment_config
        self.grid = grid  # the object maps' size: the agreement model's stem grid
        self.rng = np.random.default_rng(seed)

    def __len__(self) -> int:
        return len(self.items)

    def __getitem__(self, k: int) -> list[tuple]:
        """The draw, and the same clause on another state of the sequence where its truth is
        the other (when one is found): with the same words both true and false, the words
        alone cannot tell the truth, and the model has to look."""
        i, t = self.items[k]
        seq = self.data.sequence(i)
        state = sequence_state(seq, t)
        image = seq.image(t) if k < self.real else self.predicted.image(k - self.real)
        drawn = draw_clause(state, self.rng)
        if drawn is None:  # no object it can name: draw another state
            return self[int(self.rng.integers(len(self)))]
        text, truth, fact = drawn
        out = [self._example(image, text, truth, fact, state)]
        for u in self.rng.permutation(seq.length + 1):
            if u == t:
                continue
            other = sequence_state(seq, int(u))
            try:
                clause = parse(text, other).clauses[0]
            except SentenceError:  # a name that fits no object there
                continue
            if clause.fact.clear(other) and clause.holds(other) != truth:
                out.append(self._example(seq.image(int(u)), text, not truth, clause.fact, other))
                break
        return out

    def _example(self, image: np.ndarray, text: str, truth: bool, fact: Fact, state: State) -> tuple:
        # A shift of up to a few pixels moves the objects by under half a cell: the maps keep.
        images, _ = augment(image[None], [np.zeros((0, 7), np.float32)], self.config, self.rng)
        objects = torch.from_numpy(object_maps(state, self.grid))
        places = torch.from_numpy(place_maps(state, fact, self.grid))
        return to_chw(images)[0], text, truth, RELATION_IDS[fact.relation], objects, places


@dataclass
class ClauseBatch:
    """Examples stacked: images (B, C, H, W), clause texts, truths (B,), relation ids (B,),
    object maps (B, kinds, g, g) and place maps (B, 2, g, g) (`object_maps`, `place_maps`)."""

    images: torch.Tensor
    texts: list[str]
    truths: torch.Tensor
    relations: torch.Tensor
    objects: torch.Tensor
    places: torch.Tensor


def collate_clauses(batch) -> ClauseBatch:
    """Every draw's examples (one or two each) as one batch."""
    examples = [example for draw in batch for example in draw]
    images, texts, truths, relations, objects, places = zip(*examples, strict=True)
    return ClauseBatch(
        torch.stack(images),
        list(texts),
        torch.tensor(truths, dtype=torch.float32),
        torch.tensor(relations),
        torch.stack(objects),
        torch.stack(places),
    )
