"""The object dynamics' learning curve: side-effect error against the executions trained on.

    python benchmarks/objects_curve.py "4,000 batches:20114=runs/eval/a.json" \
        "4,000 batches:40274=runs/eval/b.json" "8,000 batches:60285=runs/eval/c.json" \
        [--out docs/objects-curve.png]

Each argument is a series' name (what its nets share, such as their number of batches; optional,
up to a colon), the number of executions a net learned from, and its report (`afford eval
dynamics --out FILE.json`, every report measured on the same data). Prints one Markdown row per
net (the median error in pixels of all side-effect objects and of each kind, the share within
3 px, the off-the-table F1) and, with --out, draws each series' median error of all side-effect
objects against the executions on a log scale.
"""

from __future__ import annotations

import argparse
import json
from dataclasses import dataclass
from pathlib import Path

from afford.errors import UserError, exit_on_user_error

KINDS = ("all side-effect objects", "pushed", "toppled", "carried", "block tips", "placed falls")
TARGET_PX = 3.0  # the median error the design asks of all side-effect objects


@dataclass
class Point:
    series: str
    executions: int
    report: dict


def read(items: list[str]) -> list[Point]:
    points = []
    for item in items:
        head, _, path = item.rpartition("=")
        series, _, count = head.rpartition(":")
        count = count.replace(",", "")
        if not count.isdigit() or not Path(path).is_file():
            raise UserError(f"{item!r}: expected [SERIES:]EXECUTIONS=FILE.json of an existing report")
        points.append(Point(series or "nets", int(count), json.loads(Path(path).read_text())))
    order = {name: i for i, name in enumerate(dict.fromkeys(p.series for p in points))}
    return sorted(points, key=lambda p: (order[p.series], p.executions))  # series as given


def median(point: Point, kind: str) -> float:
    group = point.report["groups"].get(kind)
    return float("nan") if group is None else group["median_px"]


def plot(points: list[Point], out: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(6, 4))
    for series in dict.fromkeys(p.series for p in points):
        mine = [p for p in points if p.series == series]
        ax.plot([p.executions for p in mine], [median(p, KINDS[0]) for p in mine], "o-", lw=2, label=series)
    ax.axhline(TARGET_PX, color="k", ls=":", lw=1, label=f"target ({TARGET_PX:.0f} px)")
    xs: list[int] = []
    for n in sorted({p.executions for p in points}):
        if not xs or n > 1.15 * xs[-1]:  # a tick close to the last would print over it
            xs.append(n)
    ax.set_xscale("log")
    ax.set_xticks(xs, [f"{n / 1000:.0f}k" for n in xs])
    ax.minorticks_off()
    ax.set_xlabel("executions trained on")
    ax.set_ylabel("median error, all side-effect objects (px)")
    ax.set_ylim(bottom=0)
    ax.legend(fontsize=8)
    ax.set_title("Object dynamics: where side effects land")
    fig.tight_layout()
    out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(out, dpi=120)
    plt.close(fig)


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("reports", nargs="+", metavar="[SERIES:]EXECUTIONS=FILE.json")
    p.add_argument("--out", type=Path, metavar="FILE.png", help="also draw the curve here")
    args = p.parse_args()
    points = read(args.reports)
    print("| series | executions | " + " | ".join(KINDS) + " | off the table F1 |")
    print("|---" * (len(KINDS) + 3) + "|")
    for point in points:
        cells = []
        for kind in KINDS:
            g = point.report["groups"].get(kind)
            cells.append("-" if g is None else f"{g['median_px']:.2f} ({g['within_3px']:.2f})")
        f1 = point.report["off_table_f1"]["f1"]
        print(f"| {point.series} | {point.executions:,} | " + " | ".join(cells) + f" | {f1:.2f} |")
    if args.out:
        plot(points, args.out)
        print(f"picture: {args.out}")


if __name__ == "__main__":
    exit_on_user_error(main)
