"""The scene and demo commands at toy size, for real, in a subprocess; Ctrl-C in any command."""

import json
import subprocess
import sys


def afford(*args):
    return subprocess.run(
        [sys.executable, "-m", "afford.cli.main", *args], capture_output=True, text=True, timeout=300
    )


def test_scene_picture_and_json(tmp_path):
    out = tmp_path / "s.png"
    r = afford("scene", "--seed", "3", "--out", str(out), "--json", "--save", str(tmp_path / "s.json"))
    assert r.returncode == 0, r.stderr
    data = json.loads(r.stdout)
    assert data["objects"] and data["affordances"] and out.stat().st_size > 1000
    from afford.cli.main import main  # the saved scene loads back (in this process: no start-up)

    assert main(["scene", "--load", str(tmp_path / "s.json")]) == 0


def test_bad_scene_file_gives_one_line_error(tmp_path, capsys):
    bad = tmp_path / "bad.json"
    bad.write_text('{"objects": [{"kind": "cup", "pos": [0, 1]}]}')
    r = afford("scene", "--load", str(bad))
    assert r.returncode == 2 and r.stderr.strip().count("\n") == 0 and "objects[0].pos" in r.stderr
    from afford.cli.main import main

    capsys.readouterr()
    assert main(["scene", "--load", str(tmp_path / "missing.json")]) == 2  # in this process
    assert "no such scene file" in capsys.readouterr().err


def test_demo_writes_strip(tmp_path):
    r = afford("demo", "--seed", "1", "--steps", "2", "--out", str(tmp_path / "d.png"))
    assert r.returncode == 0, r.stderr
    assert (tmp_path / "d.png").stat().st_size > 1000


def test_ctrl_c_anywhere_ends_in_one_line_with_exit_130(monkeypatch, capsys):
    import afford.cli.main as cli
    import afford.cli.scene as scene_commands

    def interrupted(args):
        raise KeyboardInterrupt  # as Ctrl-C would, in the middle of a command

    monkeypatch.setattr(scene_commands, "cmd_scene", interrupted)
    assert cli.main(["scene", "--seed", "0"]) == 130
    assert capsys.readouterr().err == "afford: interrupted\n"
