"""The object dynamics' learning curve: side-effect error against the executions trained on.

    python benchmarks/objects_curve.py 20872=runs/eval/a.json 41744=runs/eval/b.json \
        [--out docs/objects-curve.png]

Each argument is the number of executions a net learned from and its report (`afford eval
dynamics --out FILE.json`, all measured on the same data). Prints one Markdown row per net (the
median error in pixels of all side-effect objects and of each kind, the share within 3 px, the
off-the-table F1) and, with --out, draws the medians against the executions on a log scale.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

from afford.errors import UserError, exit_on_user_error

KINDS = ("all side-effect objects", "pushed", "toppled", "carried", "block tips", "placed falls")


def read(items: list[str]) -> list[tuple[int, dict]]:
    points = []
    for item in items:
        count, _, path = item.partition("=")
        if not count.isdigit() or not Path(path).is_file():
            raise UserError(f"{item!r}: expected EXECUTIONS=FILE.json of an existing report")
        points.append((int(count), json.loads(Path(path).read_text())))
    return sorted(points, key=lambda p: p[0])


def plot(points: list[tuple[int, dict]], out: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(6, 4))
    xs = [n for n, _ in points]
    for kind in KINDS:
        ys = [r["groups"][kind]["median_px"] if kind in r["groups"] else float("nan") for _, r in points]
        ax.plot(xs, ys, "o-", lw=2.5 if kind == KINDS[0] else 1, label=kind)
    ax.axhline(3, color="k", ls=":", lw=1, label="target, all (3 px)")
    ax.set_xscale("log")
    ax.set_xticks(xs, [f"{n / 1000:.0f}k" for n in xs])
    ax.minorticks_off()
    ax.set_xlabel("executions trained on")
    ax.set_ylabel("median error of side-effect objects (px)")
    ax.set_ylim(bottom=0)
    ax.legend(fontsize=7)
    ax.set_title("Object dynamics: more executions, nearer landings")
    fig.tight_layout()
    out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(out, dpi=120)
    plt.close(fig)


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("reports", nargs="+", metavar="EXECUTIONS=FILE.json")
    p.add_argument("--out", type=Path, metavar="FILE.png", help="also draw the curve here")
    args = p.parse_args()
    points = read(args.reports)
    print("| executions | " + " | ".join(KINDS) + " | off the table F1 |")
    print("|---" * (len(KINDS) + 2) + "|")
    for n, r in points:
        cells = []
        for kind in KINDS:
            g = r["groups"].get(kind)
            cells.append("-" if g is None else f"{g['median_px']:.2f} ({g['within_3px']:.2f})")
        print(f"| {n:,} | " + " | ".join(cells) + f" | {r['off_table_f1']['f1']:.2f} |")
    if args.out:
        plot(points, args.out)
        print(f"picture: {args.out}")


if __name__ == "__main__":
    exit_on_user_error(main)
