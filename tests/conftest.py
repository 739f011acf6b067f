import sys
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).parent))


@pytest.fixture(scope="module")
def scene():
    from afford.sim.scene import Scene

    s = Scene()
    yield s
    s.close()
