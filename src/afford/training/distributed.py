"""Training on several processes or machines: `afford train ...` run under torchrun.

torchrun starts one process per rank and sets RANK, WORLD_SIZE and LOCAL_WORLD_SIZE; without
them a run is the usual single process and nothing here changes it. With them the net is
wrapped in DistributedDataParallel (gloo: the training loop runs on the CPU), the preset's
batch is the global batch, split evenly over the ranks, every rank reads its own slice of
one shared data order and draws its own augmentations, and only rank 0 writes checkpoints,
logs and pictures (`training/loop.py`). A resumed run reads the same checkpoint on every rank.
"""

from __future__ import annotations

import os
from collections.abc import Iterator
from dataclasses import dataclass

import torch
import torch.distributed as dist
from torch import nn
from torch.utils.data import Sampler

BACKEND = "gloo"  # the loop trains on the CPU; gloo is torch's collective backend for it


class DistributedError(ValueError):
    """A run that cannot be split over torchrun's ranks as asked."""


@dataclass(frozen=True)
class World:
    rank: int = 0
    size: int = 1
    local_size: int = 1  # ranks on this machine, which share its cores

    @property
    def main(self) -> bool:
        return self.rank == 0


def join_world() -> World:
    """This process's place among torchrun's ranks (joining their process group once), or a
    world of one when not started by torchrun."""
    size = int(os.environ.get("WORLD_SIZE", "1"))
    if size <= 1:
        return World()
    if not dist.is_initialized():
        dist.init_process_group(BACKEND)
    return World(dist.get_rank(), dist.get_world_size(), int(os.environ.get("LOCAL_WORLD_SIZE", size)))


def leave_world() -> None:
    if dist.is_initialized():
        dist.destroy_process_group()


def is_main_process() -> bool:
    """Rank 0, or a run not under torchrun: the process that prints."""
    return os.environ.get("RANK", "0") == "0"


def rank_batch(global_batch: int, world: World) -> int:
    if global_batch % world.size:
        raise DistributedError(
            f"the batch of {global_batch} does not split evenly over {world.size} ranks; "
            "set batch_size to a multiple of --nproc_per_node x nodes"
        )
    return global_batch // world.size


def rank_threads(threads: int, world: World) -> int:
    """The preset's threads are the machine's: ranks on one machine share them."""
    return max(1, threads // world.local_size)


class RankSlice(Sampler[int]):
    """Rank r's share of another sampler's order: items r, r + size, r + 2 size, ...

    Every rank must build `base` with the same seed, so that all see one order and their
    slices are disjoint; each epoch is cut to a multiple of the world size, so every rank
    makes the same number of batches (a rank with one batch more would wait forever)."""

    def __init__(self, base: Sampler[int], world: World):
        self.base, self.world = base, world

    def __iter__(self) -> Iterator[int]:
        order = list(self.base)
        usable = len(order) - len(order) % self.world.size
        yield from order[self.world.rank : usable : self.world.size]

    def __len__(self) -> int:
        return len(self.base) // self.world.size


def loader_order(base: Sampler[int] | None, length: int, world: World, seed: int = 0) -> dict:
    """DataLoader arguments for the training order: `base` (None: a shuffle) for one process,
    this rank's slice of it under torchrun."""
    if world.size == 1:
        return {"sampler": base} if base is not None else {"shuffle": True}
    if base is None:
        base = torch.utils.data.RandomSampler(range(length), generator=torch.Generator().manual_seed(seed))
    return {"sampler": RankSlice(base, world)}


def wrap(model: nn.Module, world: World, idle_parameters: bool = False) -> nn.Module:
    """The module to run forward through: DDP averages the gradients over ranks in backward.
    `idle_parameters`: some may get no gradient in a step (the prediction net's P^a of a type
    with no action in the batch), which DDP must then look for after each forward."""
    if world.size == 1:
        return model
    return nn.parallel.DistributedDataParallel(model, find_unused_parameters=idle_parameters)


def mean_over_ranks(values: dict[str, float], world: World) -> dict[str, float]:
    """The same dict on every rank, each value averaged over the ranks (for the logged loss)."""
    if world.size == 1 or not values:
        return values
    keys = sorted(values)
    t = torch.tensor([values[k] for k in keys], dtype=torch.float64)
    dist.all_reduce(t)
    return {k: float(v) / world.size for k, v in zip(keys, t, strict=True)}
