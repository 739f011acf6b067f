"""A user's mistake ends a benchmark script with one line, not a traceback; a bug still raises."""

from pathlib import Path

import pytest

from afford.errors import UserError, exit_on_user_error


def test_a_user_error_ends_a_script_with_one_line_and_status_2(capsys):
    def main():
        raise UserError("nope: not a dataset")

    with pytest.raises(SystemExit) as ended:
        exit_on_user_error(main)
    assert ended.value.code == 2
    assert capsys.readouterr().err == "error: nope: not a dataset\n"


def test_any_other_exception_goes_through_as_the_bug_it_is():
    def main():
        raise KeyError("a bug")

    with pytest.raises(KeyError):
        exit_on_user_error(main)


def test_an_out_folder_that_cannot_be_made_ends_afford_plan_with_one_line(tmp_path, capsys):
    from afford.cli.main import main

    a_file = tmp_path / "a-file"
    a_file.write_text("")
    scene = Path(__file__).resolve().parents[1] / "tasks" / "scenes" / "cup-ball-block.json"
    args = ["plan", "--scene", str(scene), "--goal", "the cup is on the block"]
    args += ["--planner", "symbolic", "--steps", "1", "--out", str(a_file / "x")]
    assert main(args) == 2
    err = capsys.readouterr().err
    assert err == f"afford: error: --out {a_file / 'x'}: not a directory\n"


def test_a_path_that_cannot_be_written_ends_any_command_with_one_line(tmp_path, capsys):
    from afford.cli.main import main

    a_file = tmp_path / "a-file"
    a_file.write_text("")
    assert main(["scene", "--seed", "0", "--out", str(a_file / "x" / "scene.png")]) == 2
    assert capsys.readouterr().err == f"afford: error: {a_file / 'x'}: not a directory\n"
