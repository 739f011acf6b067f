"""Write each shipped weights file's recipe (afford/recipes.py) into its safetensors metadata.

    python scripts/write_recipes.py            # rewrite the files whose recipe record differs
    python scripts/write_recipes.py --check    # exit 1 if a shipped file's record differs

A file is rewritten with the very tensors it holds and its metadata kept, the recipe record
added beside it; before the new file replaces the old, every tensor is checked bit for bit
(dtype, shape and bytes) against the old file's, and the old metadata against the new.
"""

from __future__ import annotations

import argparse
import os
import sys
from pathlib import Path

import torch
from safetensors import safe_open
from safetensors.torch import load_file, save_file

from afford.recipes import RECIPES, RECORD_KEY, read_metadata, read_recipe, recipe_record, record_json
from afford.shipped import WEIGHTS


def same_tensors(a: dict[str, torch.Tensor], b: dict[str, torch.Tensor]) -> bool:
    """Bit for bit: the same names, dtypes, shapes and bytes (NaNs and signed zeros included)."""
    return a.keys() == b.keys() and all(
        a[k].dtype == b[k].dtype
        and a[k].shape == b[k].shape
        and torch.equal(a[k].reshape(-1).view(torch.uint8), b[k].reshape(-1).view(torch.uint8))
        for k in a
    )


def write_recipe(path: Path, record: str) -> None:
    old_meta = read_metadata(path)
    old = load_file(str(path))
    meta = {**old_meta, RECORD_KEY: record}
    tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp")
    try:
        save_file(old, str(tmp), metadata=meta)
        with safe_open(str(tmp), framework="pt") as f:
            new_meta = f.metadata()
        if not same_tensors(old, load_file(str(tmp))) or new_meta != meta:
            raise SystemExit(f"{path}: the rewritten file differs from the old one; left as it was")
        os.replace(tmp, path)
    finally:
        tmp.unlink(missing_ok=True)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--check", action="store_true", help="only check the shipped files' records")
    args = ap.parse_args()
    stale = []
    for name, entry in RECIPES.items():
        path = WEIGHTS / name
        if read_recipe(read_metadata(path)) == recipe_record(entry):
            continue
        stale.append(name)
        if not args.check:
            write_recipe(path, record_json(entry))
            print(f"{path}: recipe written, tensors unchanged")
    if args.check and stale:
        print(
            f"recipes out of date in: {', '.join(stale)}; run python scripts/write_recipes.py",
            file=sys.stderr,
        )
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
