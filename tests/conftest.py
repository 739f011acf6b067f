import os
import sys
from pathlib import Path

import pytest

import afford  # noqa: F401  (chooses the headless renderer before any test module imports mujoco)

sys.path.insert(0, str(Path(__file__).parent))

# Under pytest-xdist each worker shares the cores with the others: one torch thread each, set
# again after every test, since training code sets its config's count.
ONE_THREAD = bool(os.environ.get("PYTEST_XDIST_WORKER"))


@pytest.fixture(autouse=True)
def _one_torch_thread():
    if ONE_THREAD:
        import torch

        torch.set_num_threads(1)
    yield


@pytest.fixture(scope="module")
def scene():
    from afford.sim.scene import Scene

    s = Scene()
    yield s
    s.close()


SMALL_SEQUENCES, SMALL_SHARD = 6, 2
# Its 6 sequences hold turns and none, side effects and none, a place with a side effect, and a
# test split whose states list every affordance type: what the samplers' and Table 1's tests need.
SMALL_SEED = 12


@pytest.fixture(scope="session")
def pose_dataset(tmp_path_factory) -> Path:
    """A pose-only dataset of 8 sequences (seed 3, shards of 4): what the object dynamics learn from."""
    from afford.data.generate import GenerateConfig, generate

    root = tmp_path_factory.mktemp("poses") / "p"
    generate(root, GenerateConfig(sequences=8, seed=3, workers=1, shard_size=4, images=False), progress=False)
    return root


@pytest.fixture(scope="session")
def small_dataset(tmp_path_factory) -> Path:
    """A real generated dataset of 6 sequences (SMALL_SEED, 1 worker, shards of 2), made once."""
    from afford.data.generate import GenerateConfig, generate

    root = tmp_path_factory.mktemp("data") / "one-worker"
    config = GenerateConfig(sequences=SMALL_SEQUENCES, seed=SMALL_SEED, workers=1, shard_size=SMALL_SHARD)
    generate(root, config, progress=False)
    return root
