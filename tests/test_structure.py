"""The package's shape: no import circle, no import up the layers, no module too long to read."""

import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "scripts"))

import import_graph  # noqa: E402

LONGEST = 450  # lines: a module is one idea, read in one sitting


def test_no_import_circle_and_no_import_up_the_layers():
    g = import_graph.graph()
    assert len(g) > 50  # the whole package was read
    assert import_graph.cycles(g) == []
    assert import_graph.upward(g) == []


def test_a_planted_circle_and_an_upward_import_are_found():
    g = {"afford.sim.a": {"afford.sim.b"}, "afford.sim.b": {"afford.sim.a", "afford.planning.tree"}}
    assert import_graph.cycles(g) == [["afford.sim.a", "afford.sim.b"]]
    assert import_graph.upward(g) == [("afford.sim.b", "afford.planning.tree")]


def test_no_module_is_longer_than_one_sitting():
    long = {
        str(p.relative_to(ROOT)): n
        for p in (ROOT / "src" / "afford").rglob("*.py")
        if (n := len(p.read_text().splitlines())) > LONGEST
    }
    assert not long, long
