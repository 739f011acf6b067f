"""How every shipped weights file is made again: one registry of recipes, stage by stage.

A recipe (registry.py) names, for one file under `weights/`, the ordered stages (stages.py) that
make it: the datasets (`afford generate`, `afford data predict`), the training runs (`afford
train`), the calibration (`afford eval`, which writes a cut-off or a head's scaling into the run)
and the export (`afford weights export`). Each stage is one `afford` command line with the time
it took on 2 cores where that was recorded. Written once there, a recipe becomes

- the "recipe" record in the file's safetensors metadata (`recipe_record`; `afford weights info`
  prints it, scripts/write_recipes.py writes it into the shipped files without touching their
  tensors),
- `afford weights make`, which runs the stages of the files asked for in the order of `STAGES`
  and skips each stage whose stamp (`runs/stamps/NAME.json`) records the same command,
- the table of stages and times in docs/training.md (`stage_table`).

Where a detail of how a file was first made is not on record, its recipe says so (`unknown`, and
a stage's `minutes` None); where the command that makes it again differs from the one first run,
the stage's note says how.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import time
from collections.abc import Callable, Iterable
from pathlib import Path

from afford.errors import UserError
from afford.recipes.registry import RECIPES, Recipe
from afford.recipes.stages import BY_NAME, KINDS, MADE, STAGES, Stage

__all__ = ["BY_NAME", "KINDS", "MADE", "RECIPES", "STAGES", "Recipe", "Stage"]

STAMPS = Path("runs/stamps")
RECORD_KEY = "recipe"  # the safetensors metadata key beside the checkpoint's own "afford" record


class RecipeError(UserError):
    """A file or stage the registry does not know, or a stage that failed."""


def recipe(file: str) -> Recipe:
    """The recipe of a file named relative to the weights folder."""
    if file not in RECIPES:
        raise RecipeError(f"no recipe for {file!r}; the recipes are for: {', '.join(RECIPES)}")
    return RECIPES[file]


def recipe_stages(r: Recipe) -> list[Stage]:
    return [BY_NAME[name] for name in r.stages]


def training_minutes(r: Recipe) -> float | None:
    """The recorded minutes of every training stage of the recipe (None: none recorded)."""
    known = [s.minutes for s in recipe_stages(r) if s.kind == "train" and s.minutes is not None]
    return round(sum(known), 1) if known else None


def recipe_record(r: Recipe) -> dict:
    """The record written in the file's safetensors metadata under RECORD_KEY."""
    stages = recipe_stages(r)
    untimed = [s.name for s in stages if s.minutes is None]
    unknown = list(r.unknown)
    if untimed:
        unknown.append("the time of " + ", ".join(untimed))
    return {
        "file": r.file,
        "net": r.net,
        "commit": r.commit,
        "training_command": BY_NAME[r.trained].command,
        "training_minutes_2_cores": training_minutes(r),
        "stages": [s.record() for s in stages],
        "unknown": unknown,
        "make": f"afford weights make {r.file}",
    }


def record_json(r: Recipe) -> str:
    return json.dumps(recipe_record(r))


def stages_for(files: Iterable[str]) -> list[Stage]:
    """The stages that make the files, each once, in the order of STAGES."""
    wanted = {name for f in files for name in recipe(f).stages}
    return [s for s in STAGES if s.name in wanted]


def stage_table() -> str:
    """docs/training.md's table of every stage: what it runs and its time on 2 cores."""
    rows = ["| stage | command | min, 2 cores |", "|---|---|---|"]
    for s in STAGES:
        minutes = "unknown" if s.minutes is None else f"{s.minutes:g}"
        rows.append(f"| {s.name} | `{s.command}` | {minutes} |")
    return "\n".join(rows)


# ---------------------------------------------------------------------------- running stages
def stamp_path(stage: Stage, stamps: Path = STAMPS) -> Path:
    return stamps / f"{stage.name}.json"


def is_done(stage: Stage, stamps: Path = STAMPS) -> bool:
    """Done when its stamp records the same command: a stage whose recipe changed runs again."""
    path = stamp_path(stage, stamps)
    try:
        return json.loads(path.read_text()).get("command") == stage.command
    except (OSError, ValueError, AttributeError):
        return False


def run_command(stage: Stage) -> int:
    """The stage's `afford` command in a process of its own (its threads and memory its own)."""
    argv = stage.argv
    return subprocess.run([sys.executable, "-m", "afford.cli.main", *argv[1:]]).returncode


def run_stages(
    stages: Iterable[Stage],
    stamps: Path = STAMPS,
    execute: Callable[[Stage], int] = run_command,
    log: Callable[[str], None] = print,
) -> list[str]:
    """Run each stage not yet done and stamp it; the names of the stages run.

    The commands resume on their own (generation keeps whole shards, training its last
    checkpoint), so a stage stopped half-way continues where it was when run again.
    """
    ran = []
    for stage in stages:
        if is_done(stage, stamps):
            log(f"done     {stage.name}")
            continue
        log(f"running  {stage.name}: {stage.command}")
        start = time.monotonic()
        status = execute(stage)
        if status != 0:
            raise RecipeError(
                f"stage {stage.name} failed (exit status {status}): {stage.command}; run the same "
                "make again to resume it"
            )
        stamps.mkdir(parents=True, exist_ok=True)
        record = {"stage": stage.name, "command": stage.command, "minutes": (time.monotonic() - start) / 60}
        tmp = stamps / f".{stage.name}.{os.getpid()}.tmp"
        tmp.write_text(json.dumps(record, indent=2) + "\n")
        os.replace(tmp, stamp_path(stage, stamps))
        ran.append(stage.name)
    return ran


# ---------------------------------------------------------------------------- reading a file's recipe
def read_metadata(path: str | Path) -> dict[str, str]:
    """A weights file's safetensors metadata; RecipeError unless it is an afford weights file."""
    from safetensors import SafetensorError, safe_open

    path = Path(path)
    if not path.is_file():
        raise RecipeError(f"{path}: no such file")
    try:
        with safe_open(str(path), framework="pt") as f:
            metadata = f.metadata() or {}
    except (SafetensorError, OSError, ValueError) as e:
        raise RecipeError(f"{path}: not an afford weights file (not readable as safetensors: {e})") from None
    if "afford" not in metadata:
        raise RecipeError(
            f"{path}: not an afford weights file (a safetensors file without afford's metadata)"
        )
    return metadata


def read_recipe(metadata: dict[str, str]) -> dict | None:
    """The recipe record in a file's metadata, or None where none was written."""
    text = metadata.get(RECORD_KEY)
    return None if text is None else json.loads(text)
