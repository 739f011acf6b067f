"""Dataset shards as Ray tasks: on a local Ray instance, or on a cluster made with `ray start`.

Each shard is one task running `shard.make_shard`. When a worker dies, Ray runs its task
again (RETRIES), which is safe: a shard depends only on (seed, its sequence indices), so a
re-run writes the same bytes, and it is written atomically, so the dead worker left at most a
temporary file. Results come back as tasks finish, which is what feeds the progress bar.

Ray is an optional extra (`pip install 'afford[cluster]'`): nothing else in afford imports it.
On a cluster every node needs afford installed and the output folder on shared storage.
"""

from __future__ import annotations

import logging
import os
from collections.abc import Iterator

from afford.data.format import DataError
from afford.data.shard import ShardJob, ShardResult, make_shard

RETRIES = 3  # runs of a shard after the first, when its worker dies
LOCAL_OBJECT_STORE = 256 * 2**20  # bytes; results are a few numbers, so a local instance needs little
FORWARDED_ENV = ("MUJOCO_GL", "PYOPENGL_PLATFORM")  # the renderer's choice, for workers on other nodes


def run_on_ray(jobs: list[ShardJob], workers: int, address: str | None) -> Iterator[ShardResult]:
    """Yield each job's result as its task finishes. `address`: a running cluster ("auto", or
    HOST:PORT of its head); None starts a local instance with `workers` CPUs and stops it after."""
    try:
        import ray
    except ImportError:
        raise DataError("--ray needs Ray, an optional extra: pip install 'afford[cluster]'") from None
    started_here = not ray.is_initialized()
    if started_here:
        env = {k: os.environ[k] for k in FORWARDED_ENV if k in os.environ}
        where = (
            {"address": address}
            if address
            else {"num_cpus": max(1, workers), "object_store_memory": LOCAL_OBJECT_STORE}
        )
        try:
            ray.init(
                **where,
                runtime_env={"env_vars": env} if env else None,
                include_dashboard=False,
                logging_level=logging.WARNING,
                log_to_driver=False,
            )
        except (ConnectionError, RuntimeError, ValueError) as e:
            raise DataError(f"could not join the Ray cluster at {address!r}: {e}") from None
    task = ray.remote(num_cpus=1, max_retries=RETRIES)(make_shard)
    pending = [task.remote(job) for job in jobs]
    try:
        while pending:
            done, pending = ray.wait(pending, num_returns=1)
            for ref in done:
                try:
                    yield ray.get(ref)
                except ray.exceptions.RayError as e:
                    raise DataError(f"a shard failed on Ray after {RETRIES} retries: {e}") from None
    finally:
        for ref in pending:
            ray.cancel(ref, force=True)
        if started_here:
            ray.shutdown()
