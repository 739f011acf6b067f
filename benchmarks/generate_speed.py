"""Dataset generation throughput: 1 vs 2 workers, and a projection to the paper's scale.

    python benchmarks/generate_speed.py [--sequences 60] [--json]

Generates the same small dataset twice (into a temporary folder) with 1 and with 2 workers,
prints executions/s for each, the speed-up, and the time and disk size projected for the
paper's 25,850 sequences. Run it on an otherwise idle machine.
"""

from __future__ import annotations

import argparse
import json
import tempfile
from pathlib import Path

from afford.data.generate import GenerateConfig, generate

PAPER_SEQUENCES = 25_850  # paper III.B


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--sequences", type=int, default=60)
    ap.add_argument("--json", action="store_true")
    args = ap.parse_args()
    rows = {}
    with tempfile.TemporaryDirectory() as tmp:
        for workers in (1, 2):
            root = Path(tmp) / f"w{workers}"
            config = GenerateConfig(sequences=args.sequences, seed=123, workers=workers, shard_size=5)
            report = generate(root, config, progress=False)
            disk = sum(f.stat().st_size for f in root.rglob("*") if f.is_file())
            rows[workers] = {
                "seconds": round(report.seconds, 2),
                "executions": report.executions,
                "executions_per_second": round(report.executions_per_second, 2),
                "sequences_per_second": round(args.sequences / report.seconds, 3),
                "bytes_per_sequence": disk // args.sequences,
            }
    two = rows[2]
    result = {
        "sequences": args.sequences,
        "workers": rows,
        "speedup_2_vs_1": round(rows[1]["seconds"] / two["seconds"], 2),
        "paper_scale": {
            "sequences": PAPER_SEQUENCES,
            "hours_with_2_workers": round(PAPER_SEQUENCES / two["sequences_per_second"] / 3600, 2),
            "disk_gib": round(PAPER_SEQUENCES * two["bytes_per_sequence"] / 2**30, 2),
        },
    }
    if args.json:
        print(json.dumps(result, indent=2))
        return
    for w, r in rows.items():
        print(
            f"{w} worker(s): {r['executions']} executions in {r['seconds']:.1f} s = "
            f"{r['executions_per_second']:.1f} executions/s ({r['sequences_per_second']:.2f} sequences/s)"
        )
    p = result["paper_scale"]
    print(f"speed-up 1 -> 2 workers: {result['speedup_2_vs_1']:.2f}x")
    print(
        f"paper scale ({PAPER_SEQUENCES} sequences): {p['hours_with_2_workers']:.1f} h with 2 workers, "
        f"{p['disk_gib']:.2f} GiB"
    )


if __name__ == "__main__":
    from afford.errors import exit_on_user_error

    exit_on_user_error(main)
