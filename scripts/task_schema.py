"""Write the task-file tables of docs/tasks.md from `afford.planning.task_schema`.

    python scripts/task_schema.py            # rewrite the tables between their markers
    python scripts/task_schema.py --check    # exit 1 if docs/tasks.md is out of date

Each table sits between `<!-- NAME -->` and `<!-- /NAME -->`; the prose around them is the page's
own. tests/test_docs.py runs the check.
"""

from __future__ import annotations

import argparse
import re
import sys
from pathlib import Path

PAGE = Path(__file__).resolve().parent.parent / "docs" / "tasks.md"


def rewritten(text: str) -> str:
    from afford.planning.task_schema import markdown_tables

    for name, table in markdown_tables().items():
        marked = re.compile(rf"(<!-- {name} -->\n)(?:.*?\n)?(<!-- /{name} -->)", re.S)
        if not marked.search(text):
            raise SystemExit(f"{PAGE}: no <!-- {name} --> ... <!-- /{name} --> markers")
        text = marked.sub(lambda m, t=table: m.group(1) + t + "\n" + m.group(2), text)
    return text


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--check", action="store_true", help="only check that docs/tasks.md is up to date")
    args = ap.parse_args()
    text = PAGE.read_text()
    new = rewritten(text)
    if args.check:
        if new != text:
            print(f"{PAGE}'s tables are out of date: run python scripts/task_schema.py", file=sys.stderr)
            return 1
        return 0
    PAGE.write_text(new)
    print(f"wrote {PAGE}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
