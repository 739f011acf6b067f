"""The `afford` command line: one parser, a module per command group, one-line errors.

Each group (`scene.py`, `planning.py`, `data.py`, `nets.py`, `weights.py`) adds its subcommands with
`add_parsers`; every error a user can cause is an `afford.errors.UserError`, printed here as
one line with exit status 2.
"""

from __future__ import annotations

import argparse
import sys

from afford.cli import data, nets, planning, scene, weights
from afford.errors import UserError

# The command groups, in the order `afford --help` lists them.
GROUPS = (scene, planning, data, nets, weights)


def build_parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(
        prog="afford",
        description="Plan action sequences by recognising affordances in predicted futures.",
    )
    sub = p.add_subparsers(dest="command", required=True)
    for group in GROUPS:
        group.add_parsers(sub)
    return p


def main(argv: list[str] | None = None) -> int:
    from afford.training.memory import keep_freed_memory

    args = build_parser().parse_args(argv)
    keep_freed_memory()  # the nets' large tensors recur every step: keep their memory
    try:
        return args.func(args)
    except UserError as e:
        print(f"afford: error: {e}", file=sys.stderr)
        return 2
    except OSError as e:
        if e.filename is None:
            raise  # not a path the user named: a bug, with its traceback
        # A path given on the command line that cannot be read or written (a folder that is a
        # file, no permission, a full disk): the user's to fix, so one line.
        print(f"afford: error: {e.filename}: {e.strerror.lower()}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("afford: interrupted", file=sys.stderr)  # one line, not a traceback
        return 130


if __name__ == "__main__":
    sys.exit(main())
