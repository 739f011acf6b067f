"""Where training runs: the device, and the ranks of a run under torchrun.

A run trains on a GPU when one is there (`--device auto`, the default) or on the CPU; under
torchrun each rank takes the GPU of its local rank. torchrun starts one process per rank and
sets RANK, WORLD_SIZE and LOCAL_WORLD_SIZE; without them a run is the usual single process.
With them the net is wrapped in DistributedDataParallel (nccl between GPUs, gloo between
CPUs), the preset's batch is the global batch, split evenly over the ranks, every rank reads
its own slice of one shared data order and draws its own augmentations, and only rank 0
writes checkpoints, logs and pictures (`training/loop.py`). A resumed run reads the same
checkpoint on every rank. The GPU path has not been run here (no GPU was lent): on the CPU
it is the same code with every move a no-op.
"""

from __future__ import annotations

import dataclasses
import os
from collections.abc import Iterator
from dataclasses import dataclass

import torch
import torch.distributed as dist
from torch import nn
from torch.utils.data import Sampler

from afford.errors import UserError

BACKENDS = {"cpu": "gloo", "cuda": "nccl"}  # torch's collective backend for each kind of device
DEVICES = ("auto", "cpu", "cuda")


class DistributedError(UserError):
    """A run that cannot be placed or split over torchrun's ranks as asked."""


@dataclass(frozen=True)
class World:
    rank: int = 0
    size: int = 1
    local_size: int = 1  # ranks on this machine, which share its cores
    device: str = "cpu"  # where this rank's net and batches live: "cpu" or "cuda:K"

    @property
    def main(self) -> bool:
        return self.rank == 0


def resolve_device(request: str = "auto", local_rank: int = 0) -> str:
    """ "cpu" or "cuda:K" for a --device request; a GPU asked for where there is none is refused."""
    if request not in DEVICES:
        raise DistributedError(f"unknown device {request!r}; expected one of {', '.join(DEVICES)}")
    has_gpu = torch.cuda.is_available()
    if request == "cuda" and not has_gpu:
        raise DistributedError("--device cuda: torch sees no GPU here (use --device cpu or auto)")
    if request == "cpu" or not has_gpu:
        return "cpu"
    return f"cuda:{local_rank % torch.cuda.device_count()}"


def join_world(device: str = "auto") -> World:
    """This process's place among torchrun's ranks (joining their process group once) and its
    device, or a world of one when not started by torchrun."""
    size = int(os.environ.get("WORLD_SIZE", "1"))
    where = resolve_device(device, int(os.environ.get("LOCAL_RANK", "0")))
    if where.startswith("cuda"):
        torch.cuda.set_device(where)
    if size <= 1:
        return World(device=where)
    if not dist.is_initialized():
        dist.init_process_group(BACKENDS[where.split(":")[0]])
    local = int(os.environ.get("LOCAL_WORLD_SIZE", size))
    return World(dist.get_rank(), dist.get_world_size(), local, where)


def to_device(value, device: str):
    """Tensors moved to `device`, inside lists, tuples and dataclasses (a batch, targets)."""
    if isinstance(value, torch.Tensor):
        return value.to(device, non_blocking=True)
    if isinstance(value, list | tuple):
        return type(value)(to_device(v, device) for v in value)
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        return dataclasses.replace(
            value, **{f.name: to_device(getattr(value, f.name), device) for f in dataclasses.fields(value)}
        )
    return value


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
    ids = [torch.device(world.device).index] if world.device.startswith("cuda") else None
    return nn.parallel.DistributedDataParallel(model, device_ids=ids, find_unused_parameters=idle_parameters)


def mean_over_ranks(values: dict[str, float], world: World) -> dict[str, float]:
    """The same dict on every rank, each value averaged over the ranks (for the logged loss)."""
    if world.size == 1 or not values:
        return values
    keys = sorted(values)
    t = torch.tensor([values[k] for k in keys], dtype=torch.float64, device=world.device)
    dist.all_reduce(t)
    return {k: float(v) / world.size for k, v in zip(keys, t.cpu(), strict=True)}
