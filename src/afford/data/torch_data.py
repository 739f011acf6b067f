"""PyTorch datasets over a generated dataset: one for each net.

Recognition (paper II.B) learns from single states and their ground-truth affordance lists;
prediction (II.C) from runs of 1-4 executions that start at a random state of a sequence.
Images come out as (4, H, W) float32 in [0, 1]; affordance rows stay in the world frame
(format.AFF_COLUMNS) and the nets turn them into their own targets.
"""

from __future__ import annotations

import signal

import numpy as np
import torch
from torch.utils.data import Dataset as TorchDataset

from afford.data.augment import NO_AUGMENT, AugmentConfig, augment
from afford.data.effects import sequence_effects, step_mask
from afford.data.format import Dataset
from afford.images import to_chw


class RecognitionData(TorchDataset):
    """(image (4, H, W), affordance rows (n, 7)) for every state of a split."""

    def __init__(self, data: Dataset, split: str, augment_config: AugmentConfig = NO_AUGMENT, seed: int = 0):
        self.data = data
        self.items = [(i, t) for i in data.indices(split) for t in range(data.sequence(i).length + 1)]
        self.config = augment_config
        self.rng = np.random.default_rng(seed)

    def __len__(self) -> int:
        return len(self.items)

    def __getitem__(self, k: int) -> tuple[torch.Tensor, torch.Tensor]:
        i, t = self.items[k]
        seq = self.data.sequence(i)
        images, (rows,) = augment(seq.image(t)[None], [seq.affordances[t]], self.config, self.rng)
        return to_chw(images)[0], torch.from_numpy(rows)


def collate_recognition(batch) -> tuple[torch.Tensor, list[torch.Tensor]]:
    """Images stacked; the affordance lists stay a list (their lengths differ)."""
    return torch.stack([b[0] for b in batch]), [b[1] for b in batch]


class PredictionData(TorchDataset):
    """A run of L = 1..max_steps executions from a random start state of a sequence.

    Returns images (L+1, 4, H, W) and actions (L, 7); with `effect_masks`, also (L, H, W) masks
    of where each step had a side effect (data/effects.py), moved with the images by the
    augmentation: the labels of a two-outcome net's training. With `random_start` off, every
    run starts at state 0 and takes as many steps as the sequence has (for evaluation per step).
    """

    def __init__(
        self,
        data: Dataset,
        split: str,
        max_steps: int = 4,
        augment_config: AugmentConfig = NO_AUGMENT,
        random_start: bool = True,
        seed: int = 0,
        effect_masks: bool = False,
    ):
        self.data = data
        self.indices = [i for i in data.indices(split) if data.sequence(i).length > 0]
        self.max_steps = max_steps
        self.config = augment_config
        self.random_start = random_start
        self.rng = np.random.default_rng(seed)
        self.effect_masks = effect_masks
        self._labels: dict[int, list] = {}  # a sequence's effect labels, made once per process

    def __len__(self) -> int:
        return len(self.indices)

    def __getitem__(self, k: int) -> tuple[torch.Tensor, ...]:
        seq = self.data.sequence(self.indices[k])
        start = int(self.rng.integers(seq.length)) if self.random_start else 0
        stop = min(seq.length, start + self.max_steps)
        images = np.stack([seq.image(t) for t in range(start, stop + 1)])
        if self.effect_masks:  # a fifth channel, so that shifts and mirrors move it with the image
            masks = _effect_masks(self, seq, start, stop)
            images = np.concatenate([images, masks[..., None]], -1)
        images, (actions,) = augment(images, [seq.actions[start:stop]], self.config, self.rng, noisy=[True])
        if self.effect_masks:
            return (
                to_chw(images[..., :-1]),
                torch.from_numpy(actions),
                torch.from_numpy(images[1:, ..., -1] > 0.5),
            )
        return to_chw(images), torch.from_numpy(actions)


class JoinedData(TorchDataset):
    """Several `PredictionData` (one per dataset) as one: runs of part 0, then of part 1, ...
    Setting `rng` (a DataLoader worker's stream, `worker_init`) gives each part its own."""

    def __init__(self, parts: list[PredictionData]):
        self.parts = parts
        self.starts = np.cumsum([0] + [len(p) for p in parts])

    def __len__(self) -> int:
        return int(self.starts[-1])

    def __getitem__(self, k: int) -> tuple[torch.Tensor, ...]:
        part = int(np.searchsorted(self.starts, k, side="right")) - 1
        return self.parts[part][k - int(self.starts[part])]

    @property
    def rng(self) -> np.random.Generator:
        return self.parts[0].rng

    @rng.setter
    def rng(self, rng: np.random.Generator) -> None:
        for part, stream in zip(self.parts, rng.spawn(len(self.parts)), strict=True):
            part.rng = stream


def _effect_masks(data: PredictionData, seq, start: int, stop: int) -> np.ndarray:
    """(stop - start + 1, H, W) float32: state t's mask shows where step t - 1 had a side effect
    (the start state's is empty)."""
    if seq.index not in data._labels:
        data._labels[seq.index] = sequence_effects(seq)
    labels = data._labels[seq.index]
    masks = np.zeros((stop - start + 1, *seq.rgb.shape[1:3]), np.float32)
    for t in range(start, stop):
        if not labels[t].canonical:
            masks[t - start + 1] = step_mask(labels[t], seq.poses[t], seq.poses[t + 1], seq.actions[t])
    return masks


def collate_prediction(batch) -> tuple[torch.Tensor, ...]:
    """Pad runs to the longest: images (B, L+1, 4, H, W), actions (B, L, 7), steps (B,), and
    with effect masks, effects (B, L, H, W)."""
    steps = torch.tensor([len(b[1]) for b in batch])
    longest = int(steps.max())
    images = torch.zeros((len(batch), longest + 1, *batch[0][0].shape[1:]))
    actions = torch.zeros((len(batch), longest, 7))
    for j, (im, act, *_) in enumerate(batch):
        images[j, : len(im)] = im
        actions[j, : len(act)] = act
    if len(batch[0]) == 2:
        return images, actions, steps
    effects = torch.zeros((len(batch), longest, *batch[0][0].shape[2:]), dtype=torch.bool)
    for j, (_, _, fx_masks) in enumerate(batch):
        effects[j, : len(fx_masks)] = fx_masks
    return images, actions, steps, effects


def worker_init(worker_id: int) -> None:
    """DataLoader workers: each its own augmentation stream, and deaf to Ctrl-C and SIGTERM.

    A stop signal sent to the whole process group (Ctrl-C in a terminal, `pkill -f`) reaches the
    workers too; a worker that died of it made the training loop fail on the lost worker before
    it could save its checkpoint. Ignoring it here leaves the stop to the loop, which saves
    RUN/last.safetensors and then ends its workers itself.
    """
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    signal.signal(signal.SIGTERM, signal.SIG_IGN)
    info = torch.utils.data.get_worker_info()
    info.dataset.rng = np.random.default_rng([info.seed % 2**32, worker_id])
