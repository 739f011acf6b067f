"""Goal reading speed: how long `parse` takes to read each sentence of the goal grammar's test
set (tests/goal_sentences.json) in its scene, refusals (with their suggestion) included.

    python benchmarks/goal_reading.py [--repeats 3] [--json]

Each sentence is read `--repeats` times and its fastest time kept (the machine's other work
shows up as slower reads, not as the reader's cost); the grammar is built once before timing,
and that build is reported apart. Target: under 50 ms a sentence.
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np

SENTENCES = Path(__file__).resolve().parents[1] / "tests" / "goal_sentences.json"
TARGET_MS = 50.0


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--json", action="store_true")
    args = ap.parse_args()

    from afford.sim.specs import specs_from_json
    from afford.words import grammar
    from afford.words.facts import State
    from afford.words.sentences import SentenceError, parse

    data = json.loads(SENTENCES.read_text())
    states = {name: State.of_specs(specs_from_json(scene)) for name, scene in data["scenes"].items()}
    t = time.perf_counter()
    grammar.parser()
    build_ms = (time.perf_counter() - t) * 1000

    def fastest(case: dict) -> float:
        best = float("inf")
        for _ in range(max(1, args.repeats)):
            t = time.perf_counter()
            try:
                parse(case["text"], states[case["scene"]])
            except SentenceError:
                pass
            best = min(best, time.perf_counter() - t)
        return best * 1000

    rows = {kind: [(case["text"], fastest(case)) for case in data[kind]] for kind in ("read", "refuse")}
    every = [ms for kind in rows.values() for _, ms in kind]
    slowest = max((row for kind in rows.values() for row in kind), key=lambda r: r[1])
    result = {
        "sentences": len(every),
        "median_ms": round(float(np.median(every)), 2),
        "max_ms": round(float(np.max(every)), 2),
        "slowest": slowest[0],
        "by_kind": {
            kind: {
                "median_ms": round(float(np.median([ms for _, ms in r])), 2),
                "max_ms": round(max(ms for _, ms in r), 2),
            }
            for kind, r in rows.items()
        },
        "grammar_build_ms": round(build_ms, 1),
        "target_ms": TARGET_MS,
        "under_target": bool(np.max(every) < TARGET_MS),
    }
    if args.json:
        print(json.dumps(result, indent=2))
    else:
        read, refused = result["by_kind"]["read"], result["by_kind"]["refuse"]
        verdict = "met" if result["under_target"] else "missed"
        print(
            f"goal reading, {result['sentences']} sentences: median {result['median_ms']:.1f} ms, "
            f"max {result['max_ms']:.1f} ms ({slowest[0]!r}); read {read['median_ms']:.1f} / "
            f"{read['max_ms']:.1f} ms, refused {refused['median_ms']:.1f} / {refused['max_ms']:.1f} ms "
            f"(median / max); grammar built once in {build_ms:.0f} ms; under {TARGET_MS:.0f} ms: {verdict}"
        )


if __name__ == "__main__":
    from afford.errors import exit_on_user_error

    exit_on_user_error(main)
