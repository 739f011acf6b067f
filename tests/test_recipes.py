"""The shipped weights' recipes (afford/recipes/): written once, carried by every shipped file,
parsed by afford's own parser, and run stage by stage by `afford weights make`."""

from __future__ import annotations

import json
from dataclasses import asdict, replace
from importlib import import_module
from pathlib import Path

import pytest

from afford.cli.main import build_parser, main
from afford.recipes import (
    BY_NAME,
    KINDS,
    RECIPES,
    STAGES,
    RecipeError,
    Stage,
    read_metadata,
    read_recipe,
    recipe_record,
    run_stages,
    stage_table,
    stages_for,
)
from afford.shipped import WEIGHTS
from afford.training.fields import flat, from_dict, with_fields
from afford.training.overrides import apply_overrides, preset_config

ROOT = Path(__file__).resolve().parents[1]
# Where each `afford train NET` takes its presets from.
PRESETS_OF = {
    "goals": "afford.words.config",
    "recognition": "afford.recognition.config",
    "prediction": "afford.prediction.config",
    "dynamics": "afford.objects.dynamics",
    "perception": "afford.objects.perception",
}
# Config fields fitted after training (calibrations, which export writes into the config) or
# filled in by training itself (the agreement model's vocabulary): not the recipe's to set.
FITTED = {
    "choice_scale",
    "choice_bias",
    "choice_scales",
    "choice_biases",
    "vocabulary",
    "outcome_temperature",
}
# The options of a stage that name what it reads, and the one that names what it makes.
READS = ("data", "more_data", "init", "predicted", "prediction", "run", "dir")


def shipped_files() -> list[str]:
    return sorted(p.relative_to(WEIGHTS).as_posix() for p in WEIGHTS.rglob("*.safetensors"))


def parse(stage: Stage):
    argv = stage.argv
    assert argv[0] == "afford", stage.command
    return build_parser().parse_args(argv[1:])


def stored_config(file: str) -> dict:
    return json.loads(read_metadata(WEIGHTS / file)["afford"])["config"]


def trained_config(stage: Stage):
    """The config a training stage's command gives its net, built as `afford train` builds it."""
    args = parse(stage)
    PRESETS = import_module(PRESETS_OF[args.net]).PRESETS
    given = {"steps": args.steps, "threads": args.threads}
    if args.net == "prediction":
        given["pixel_input"] = not args.no_affordance_pixel
    return apply_overrides(preset_config(PRESETS, args.preset, **given), args.set)


def differences(config, stored: dict) -> dict:
    """Training fields where a config and a file's stored config (flat or grouped) differ; a
    field the file does not record (added to afford after it was trained) must be at its
    default, which is what ran."""
    theirs = flat(from_dict(type(config), stored))
    return {
        name: (mine, theirs[name])
        for name, mine in flat(config).items()
        if name.rpartition(".")[2] not in FITTED and json.dumps(mine) != json.dumps(theirs[name])
    }


# ------------------------------------------------------------------ the registry
def test_every_shipped_file_has_a_recipe_and_every_recipe_a_shipped_file():
    assert sorted(RECIPES) == shipped_files(), "a shipped file without a recipe, or a recipe without its file"
    assert {"recognition.safetensors", "prediction.safetensors", "agreement.safetensors"} <= set(RECIPES)


def test_every_shipped_files_metadata_carries_the_registrys_recipe():
    for file, entry in RECIPES.items():
        assert read_recipe(read_metadata(WEIGHTS / file)) == recipe_record(entry), (
            f"{file}: its recipe differs from afford/recipes: run python scripts/write_recipes.py"
        )


def test_the_stages_are_named_once_and_each_recipe_runs_them_in_the_registrys_order():
    assert len(BY_NAME) == len(STAGES)
    order = {s.name: k for k, s in enumerate(STAGES)}
    for entry in RECIPES.values():
        assert all(name in BY_NAME for name in entry.stages), entry.file
        assert [order[n] for n in entry.stages] == sorted(order[n] for n in entry.stages), entry.file
        assert entry.trained in entry.stages and BY_NAME[entry.trained].kind == "train"
        kinds = [BY_NAME[n].kind for n in entry.stages]
        assert kinds[-1] == "export" and kinds.count("export") == 1, entry.file
    assert all(s.kind in KINDS for s in STAGES)


def test_every_command_parses_with_affords_own_parser_and_reads_only_what_an_earlier_stage_made():
    made: list[str] = []
    for stage in STAGES:
        args = parse(stage)
        for option in READS:
            # `afford data predict DIR` keeps its subcommand's name in `data`: it reads DIR.
            value = None if args.command == option == "data" else getattr(args, option, None)
            for path in value if isinstance(value, list) else [value] if value else []:
                assert any(path == m or path.startswith(m + "/") for m in made), (
                    f"{stage.name} reads {path}, which no stage before it makes"
                )
        if getattr(args, "out", None):
            made.append(args.out)


def test_each_export_writes_its_files_name_from_the_run_its_recipe_trained():
    for entry in RECIPES.values():
        export = parse(BY_NAME[entry.stages[-1]])
        assert (export.command, export.weights, export.file) == ("weights", "export", entry.file)
        assert export.run == parse(BY_NAME[entry.trained]).out


def test_each_recipes_training_command_gives_the_config_stored_in_its_shipped_file():
    for entry in RECIPES.values():
        config = trained_config(BY_NAME[entry.trained])
        assert differences(config, stored_config(entry.file)) == {}, entry.file


def test_each_shipped_files_stored_config_is_its_preset_but_for_what_its_recipe_sets():
    """The preset a recipe names holds every field of the file's stored config that the
    recipe's command does not set itself (--set, --steps, --threads), so a preset (or the
    defaults) is the shipped recipe, not a value the commands must remember to override."""
    from afford.training.fields import paths

    for entry in RECIPES.values():
        args = parse(BY_NAME[entry.trained])
        PRESETS = import_module(PRESETS_OF[args.net]).PRESETS
        preset = PRESETS[args.preset]
        known = paths(type(preset))
        named = {known[pair.split("=", 1)[0]] for pair in args.set or ()}
        named |= {known[k] for k in ("steps", "threads") if getattr(args, k, None) is not None}
        differ = differences(preset, stored_config(entry.file))
        assert {tuple(k.split(".")) if "." in k else known[k] for k in differ} <= named, (entry.file, differ)


def test_the_prediction_configs_defaults_are_the_shipped_prediction_nets_recipe():
    from afford.prediction.config import PRESETS, PredictionConfig

    assert PredictionConfig() == PRESETS["cpu-two-outcome"]
    assert differences(PredictionConfig(), stored_config("prediction.safetensors")) == {}


def test_the_cpu_two_outcome_preset_is_the_shipped_prediction_nets_config():
    from afford.prediction.config import PRESETS
    from afford.training.checkpoint import read_checkpoint

    _, meta = read_checkpoint(WEIGHTS / "prediction.safetensors", "prediction")
    assert differences(PRESETS["cpu-two-outcome"], meta["config"]) == {}
    assert differences(PRESETS["cpu"], meta["config"]).keys() == {
        "outcomes.hypotheses",
        "outcomes.hypotheses_by",
        "outcomes.fork",
        "sampling.effect_fraction",
        "training.grad_clip",
    }


def test_the_training_docs_show_every_stage_with_its_time():
    assert stage_table() in (ROOT / "docs" / "training.md").read_text(), (
        "docs/training.md's table of stages differs from afford/recipes: paste stage_table()"
    )


# ------------------------------------------------------------------ afford weights info / export
def test_weights_info_prints_a_shipped_files_recipe(capsys):
    assert main(["weights", "info", "continuous/prediction.safetensors"]) == 0
    text = capsys.readouterr().out
    assert "4aab0f6" in text and "--set turn_fraction=0.7" in text and "[31 min]" in text
    assert main(["weights", "info", str(WEIGHTS / "prediction.safetensors"), "--json"]) == 0
    info = json.loads(capsys.readouterr().out)
    assert info["kind"] == "prediction" and info["recipe"] == recipe_record(RECIPES["prediction.safetensors"])
    assert main(["weights", "info", "--json"]) == 0
    assert len(json.loads(capsys.readouterr().out)) == len(shipped_files())


def test_weights_info_on_a_file_that_is_not_afford_weights_is_one_line(tmp_path, capsys):
    import torch
    from safetensors.torch import save_file

    junk = tmp_path / "junk.safetensors"
    junk.write_bytes(b"not a safetensors file at all")
    bare = tmp_path / "bare.safetensors"
    save_file({"w": torch.zeros(2)}, str(bare))
    for path in (junk, bare, tmp_path / "missing.safetensors"):
        assert main(["weights", "info", str(path)]) == 2
        err = capsys.readouterr().err.strip()
        assert err.startswith(f"afford: error: {path}") and "\n" not in err
    assert "not an afford weights file" in (main(["weights", "info", str(bare)]), capsys.readouterr().err)[1]


def test_weights_export_writes_a_run_as_a_file_of_the_layout_with_its_recipe_only_from_its_run(
    tmp_path, capsys, monkeypatch
):
    from afford.prediction.config import PRESETS
    from afford.prediction.evaluate import load_net
    from afford.prediction.model import PredictionNet
    from afford.training.checkpoint import save_checkpoint

    monkeypatch.chdir(tmp_path)  # the recipe's run, runs/turns, is relative to where make runs
    config = with_fields(PRESETS["tiny"], hypotheses=2, hypotheses_by="effect", fork="latent")
    for run in ("runs/turns", "mine"):
        save_checkpoint(
            Path(run) / "best.safetensors", PredictionNet(config), "prediction", asdict(config), 1
        )
        (Path(run) / "calibration.json").write_text(json.dumps({"choice_scale": 0.5, "choice_bias": -1.0}))
    nested = ["weights", "export", "continuous/prediction.safetensors"]
    assert main([*nested, "--run", "runs/turns", "--out", "w"]) == 0
    out = tmp_path / "w" / "continuous" / "prediction.safetensors"
    assert read_recipe(read_metadata(out)) == recipe_record(RECIPES["continuous/prediction.safetensors"])
    _, loaded = load_net(out)
    assert (loaded.outcomes.choice_scale, loaded.outcomes.choice_bias) == (0.5, -1.0)
    # another run: the same file, and no shipped recipe claimed for it
    assert main([*nested, "--run", "mine", "--out", "other"]) == 0
    assert read_recipe(read_metadata(tmp_path / "other" / "continuous" / "prediction.safetensors")) is None
    capsys.readouterr()
    for unknown in (
        "nope.safetensors",
        "continuous/prediction-7.safetensors",
        "ensemble/prediction-2.safetensors",
    ):
        assert main(["weights", "export", unknown, "--run", "mine", "--out", "x"]) == 2
        assert "not a file of the weights layout" in capsys.readouterr().err
    assert main(["weights", "export", "recognition.safetensors", "--run", "mine", "--out", "x"]) == 2
    assert "holds a recognition net" in capsys.readouterr().err


# ------------------------------------------------------------------ afford weights make's stages
def test_the_stage_runner_skips_a_stage_whose_stamp_records_its_command(tmp_path):
    first, second = Stage("one", "data", "afford one", 1), Stage("two", "train", "afford two", None)
    ran: list[str] = []

    def execute(stage: Stage) -> int:
        ran.append(stage.name)
        return 0

    stamps = tmp_path / "stamps"
    assert run_stages([first], stamps, execute, log=lambda _: None) == ["one"]
    assert run_stages([first, second], stamps, execute, log=lambda _: None) == ["two"]
    assert ran == ["one", "two"] and json.loads((stamps / "two.json").read_text())["command"] == "afford two"
    changed = replace(first, command="afford one --more")  # a recipe that changed runs again
    assert run_stages([changed, second], stamps, execute, log=lambda _: None) == ["one"]
    failing = Stage("three", "export", "afford three", None)
    with pytest.raises(RecipeError, match="stage three failed"):
        run_stages([failing], stamps, lambda s: 1, log=lambda _: None)
    assert not (stamps / "three.json").exists()


def test_weights_make_runs_the_stages_of_the_files_asked_for(capsys):
    names = [s.name for s in stages_for(["prediction.safetensors"])]
    assert names == list(RECIPES["prediction.safetensors"].stages)
    both = stages_for(["prediction.safetensors", "continuous/prediction.safetensors"])
    assert len(both) == len({s.name for s in both}) and "train-prediction" in {s.name for s in both}
    assert main(["weights", "make", "nope.safetensors", "--dry-run"]) == 2
    assert "no recipe" in capsys.readouterr().err


# ------------------------------------------------------------------ data/part: the default dataset's splits
def test_generate_with_the_splits_of_a_larger_dataset(tmp_path):
    from afford.data.format import DataError
    from afford.data.generate import GenerateConfig, prepare

    config = GenerateConfig(sequences=5200, seed=0, splits_of=10000)
    manifest = prepare(tmp_path / "part", config)  # the manifest alone: no sequence is made
    assert manifest.splits == {"val": [0, 188], "test": [188, 376], "train": [376, 5200]}
    assert prepare(tmp_path / "part", config).splits == manifest.splits  # resumes
    with pytest.raises(DataError, match="--splits-of"):
        prepare(tmp_path / "part", replace(config, splits_of=None))
    assert prepare(tmp_path / "own", replace(config, splits_of=None)).splits["test"] == [98, 196]
    with pytest.raises(DataError, match="more than 300 sequences"):
        prepare(tmp_path / "small", GenerateConfig(sequences=300, splits_of=10000))
