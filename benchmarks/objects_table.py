"""The object dynamics' reports (`afford eval dynamics --out FILE.json`) side by side, as the
Markdown tables of docs/objects.md and docs/experiments/objects-dynamics.md.

    python benchmarks/objects_table.py NAME=runs/eval/a.json NAME=runs/eval/b.json [--groups G,G]

One row per report: the median error in pixels (and the share within 3 px) of each chosen group
of objects, the off-the-table F1 and the outcomes' calibration gap; copying the start first,
from the first report.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

from afford.errors import UserError, exit_on_user_error

GROUPS = (
    "acted on (grasp)",
    "acted on (place)",
    "acted on (turn)",
    "all side-effect objects",
    "pushed",
    "toppled",
    "carried",
    "block tips",
    "placed falls",
    "still",
)


def median(report: dict, group: str) -> str:
    g = report["groups"].get(group)
    return "-" if g is None else f"{g['median_px']:.2f} ({g['within_3px']:.2f})"


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("reports", nargs="+", metavar="NAME=FILE.json")
    p.add_argument("--groups", default=",".join(GROUPS), help="comma list of groups (default: the main ones)")
    args = p.parse_args()
    rows = []
    for item in args.reports:
        name, _, path = item.partition("=")
        if not path or not Path(path).is_file():
            raise UserError(f"{item!r}: expected NAME=FILE.json of an existing report")
        rows.append((name, json.loads(Path(path).read_text())))
    groups = [g for g in args.groups.split(",") if g]
    print("| model | " + " | ".join(groups) + " | off the table F1 | calibration gap |")
    print("|---" * (len(groups) + 3) + "|")
    first = rows[0][1]["groups"]
    copy = [f"{first[g]['copy_median_px']:.1f}" if g in first else "-" for g in groups]
    print("| copy the start | " + " | ".join(copy) + " | - | - |")
    for name, r in rows:
        gap = r["calibration"]["largest_gap"]
        tail = f" | {r['off_table_f1']['f1']:.2f} | " + ("-" if gap is None else f"{gap:.2f}") + " |"
        print(f"| {name} | " + " | ".join(median(r, g) for g in groups) + tail)


if __name__ == "__main__":
    exit_on_user_error(main)
