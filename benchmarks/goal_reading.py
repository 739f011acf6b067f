"""Goal reading speed: how long `parse` takes to read each sentence of the goal grammar's test
sets in its scene, refusals (with their suggestion) included: the hand-written set
(tests/goal_sentences.json) and those written cold, without the grammar at hand
(tests/goal_sentences_cold.json, _heldout.json to _heldout6.json, _writers.json; their scenes
are the first set's).

    python benchmarks/goal_reading.py [--repeats 3] [--sets NAME ...] [--json]

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

TESTS = Path(__file__).resolve().parents[1] / "tests"
SETS = {
    "hand": "goal_sentences.json",
    "cold": "goal_sentences_cold.json",
    "heldout": "goal_sentences_heldout.json",
    "heldout2": "goal_sentences_heldout2.json",
    "heldout3": "goal_sentences_heldout3.json",
    "writers": "goal_sentences_writers.json",
    "heldout4": "goal_sentences_heldout4.json",
    "heldout5": "goal_sentences_heldout5.json",
    "heldout6": "goal_sentences_heldout6.json",
}
TARGET_MS = 50.0


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--sets", nargs="+", choices=sorted(SETS), default=list(SETS))
    ap.add_argument("--json", action="store_true")
    args = ap.parse_args()

    from afford.sim.specs import specs_from_json
    from afford.words import grammar
    from afford.words.facts import State
    from afford.words.sentences import SentenceError, parse

    scenes = json.loads((TESTS / SETS["hand"]).read_text())["scenes"]
    states = {name: State.of_specs(specs_from_json(scene)) for name, scene in scenes.items()}
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

    rows: dict[str, list[tuple[str, float]]] = {"read": [], "refuse": []}
    per_set = {}
    for name in args.sets:
        data = json.loads((TESTS / SETS[name]).read_text())
        timed = {kind: [(case["text"], fastest(case)) for case in data[kind]] for kind in rows}
        for kind in rows:
            rows[kind] += timed[kind]
        every = [ms for kind in timed.values() for _, ms in kind]
        per_set[name] = {
            "sentences": len(every),
            "median_ms": round(float(np.median(every)), 2),
            "max_ms": round(float(np.max(every)), 2),
        }
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
        "by_set": per_set,
        "grammar_build_ms": round(build_ms, 1),
        "target_ms": TARGET_MS,
        "under_target": bool(np.max(every) < TARGET_MS),
    }
    if args.json:
        print(json.dumps(result, indent=2))
    else:
        read, refused = result["by_kind"]["read"], result["by_kind"]["refuse"]
        verdict = "met" if result["under_target"] else "missed"
        sets = ", ".join(
            f"{n} {s['sentences']}: {s['median_ms']:.1f} / {s['max_ms']:.1f}" for n, s in per_set.items()
        )
        print(
            f"goal reading, {result['sentences']} sentences: median {result['median_ms']:.1f} ms, "
            f"max {result['max_ms']:.1f} ms ({slowest[0]!r}); read {read['median_ms']:.1f} / "
            f"{read['max_ms']:.1f} ms, refused {refused['median_ms']:.1f} / {refused['max_ms']:.1f} ms "
            f"(median / max); by set ({sets}); grammar built once in {build_ms:.0f} ms; "
            f"under {TARGET_MS:.0f} ms: {verdict}"
        )


if __name__ == "__main__":
    from afford.errors import exit_on_user_error

    exit_on_user_error(main)
