"""The README and docs/ promise commands, links and pictures: each must exist."""

import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PAGES = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]
LINK = re.compile(r"!?\[[^\]]*\]\(([^)\s]+)\)")
COMMAND = re.compile(r"(?:^|[\s`(])afford((?: +[a-z][a-z|-]*)+)")
SCRIPT = re.compile(r"python3? ((?:benchmarks|scripts)/[\w/]+\.py)")
CODE = re.compile(r"```.*?```|`[^`\n]+`", re.S)  # fenced blocks and inline code: what a reader runs


def code(page: Path) -> str:
    """The page's code, without the comments in it (they are prose)."""
    text = "\n".join(CODE.findall(page.read_text()))
    return "\n".join(line.split(" #")[0] for line in text.splitlines() if not line.lstrip().startswith("#"))


def subcommands(parser):
    for action in parser._actions:
        if action.__class__.__name__ == "_SubParsersAction":
            return action.choices
    return {}


def shown_commands() -> set[tuple[str, ...]]:
    """Every `afford WORD [WORD]` in the pages, as command paths (a|b alternatives expanded)."""
    from afford.cli.main import build_parser

    found = set()
    for page in PAGES:
        for m in COMMAND.finditer(code(page)):
            words = m.group(1).split()
            paths = [()]
            parser_level = [build_parser()]
            for word in words:
                choices = [w for w in word.split("|") if w]
                known = subcommands(parser_level[0])
                if not known or not all(c in known for c in choices):
                    break
                paths = [(*p, c) for p in paths for c in choices]
                parser_level = [known[choices[0]]]
            found.update(p for p in paths if p)
            if not any(paths[0]):
                found.add(("?", words[0], page.name))
    return found


def test_every_command_in_the_readme_and_docs_exists_and_its_help_runs(capsys):
    from afford.cli.main import main

    commands = shown_commands()
    unknown = sorted(c for c in commands if c[0] == "?")
    assert not unknown, f"commands in the docs that afford does not have: {unknown}"
    assert ("plan",) in commands and ("bench", "tasks") in commands and ("eval", "prediction") in commands
    for path in sorted(commands):
        with pytest.raises(SystemExit) as e:
            main([*path, "--help"])
        assert e.value.code == 0, path
    capsys.readouterr()


def test_every_relative_link_and_picture_resolves():
    broken = []
    for page in PAGES:
        for target in LINK.findall(page.read_text()):
            if re.match(r"[a-z]+:", target) or target.startswith("#"):
                continue
            path = target.split("#")[0]
            if not (page.parent / path).exists():
                broken.append(f"{page.relative_to(ROOT)}: {target}")
    assert not broken, broken


def test_every_script_the_docs_run_exists():
    missing = [
        f"{page.name}: {s}"
        for page in PAGES
        for s in SCRIPT.findall(page.read_text())
        if not (ROOT / s).is_file()
    ]
    assert not missing, missing


def test_the_cli_reference_is_generated_from_the_commands_as_they_are():
    run = subprocess.run(
        [sys.executable, str(ROOT / "scripts" / "cli_reference.py"), "--check"], capture_output=True
    )
    assert run.returncode == 0, run.stderr.decode()
