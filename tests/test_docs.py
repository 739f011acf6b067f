"""The README and docs/ promise commands, links and pictures: each must exist."""

import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PAGES = [ROOT / "README.md", *sorted((ROOT / "docs").rglob("*.md"))]
LINK = re.compile(r"!?\[[^\]]*\]\(([^)\s]+)\)")
COMMAND = re.compile(r"(?:^|[\s`(])afford((?: +[a-z][a-z|-]*)+)")
SCRIPT = re.compile(r"python3? ((?:benchmarks|scripts)/[\w/]+\.py)")
CODE = re.compile(
    r"```.*?```|`[^`]+`", re.S
)  # fenced blocks and inline code (which may wrap): what a reader runs


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


CHECKOUT = re.compile(r"`git checkout ([0-9a-f]{7,40})`")


def at_commit(commit: str, path: str) -> bool:
    """Whether the repository's `commit` holds `path`; true where the clone lacks the commit
    (a shallow clone holds no history to check against)."""

    def holds(obj: str) -> bool:
        return subprocess.run(["git", "cat-file", "-e", obj], cwd=ROOT, capture_output=True).returncode == 0

    return holds(f"{commit}:{path}") or not holds(f"{commit}^{{commit}}")


def test_every_script_the_docs_run_exists():
    """In the tree, or at a commit the page has its reader check out (`git checkout C`)."""
    missing = [
        f"{page.name}: {s}"
        for page in PAGES
        for s in SCRIPT.findall(page.read_text())
        if not (ROOT / s).is_file() and not any(at_commit(c, s) for c in CHECKOUT.findall(page.read_text()))
    ]
    assert not missing, missing


def test_the_cli_reference_is_generated_from_the_commands_as_they_are():
    run = subprocess.run(
        [sys.executable, str(ROOT / "scripts" / "cli_reference.py"), "--check"], capture_output=True
    )
    assert run.returncode == 0, run.stderr.decode()


# ------------------------------------------------------------------ flags next to a command
SEPARATORS = re.compile(r";|&&|\|\||\s\|\s")
FLAG = re.compile(r"^[\[(]*(--[a-z][a-z0-9-]*)")


def command_lines(page: Path):
    """Each command line a reader would run from the page's code: fenced lines with their
    continuations joined, an inline span as one line; comments dropped."""
    for chunk in CODE.findall(page.read_text()):
        if chunk.startswith("```"):
            body = chunk.strip("`").split("\n", 1)[-1].replace("\\\n", " ")
            lines = body.splitlines()
        else:
            lines = [chunk.strip("`").replace("\n", " ")]
        for line in lines:
            line = line.split(" #")[0]
            if line.lstrip().startswith("#"):
                continue
            yield from (part.split() for part in SEPARATORS.split(line))


def leaves(parser) -> list:
    known = subcommands(parser)
    return [leaf for sub in known.values() for leaf in leaves(sub)] if known else [parser]


def flags_beside_commands(page: Path):
    """(command as written, the parsers it may mean per alternative, the flags beside it)."""
    from afford.cli.main import build_parser

    for tokens in command_lines(page):
        starts = [
            i for i, t in enumerate(tokens) if t == "afford" or t.endswith(("/afford", "afford.cli.main"))
        ]
        if not starts:
            continue
        rest = tokens[starts[0] + 1 :]
        alternatives, words = [build_parser()], []
        for word in rest:
            choices = [w for w in word.split("|") if w]
            known = subcommands(alternatives[0])
            if not known or not choices or not all(c in known for c in choices):
                break
            words.append(word)
            alternatives = [known[c] for c in choices]
        flags = {m.group(1) for t in rest if (m := FLAG.match(t))}
        if flags:
            yield " ".join(["afford", *words]), [leaves(a) for a in alternatives], flags


def test_every_flag_beside_a_command_is_one_that_command_takes():
    stale = set()
    for page in PAGES:
        for command, alternatives, flags in flags_beside_commands(page):
            for flag in flags:
                if not all(any(flag in p._option_string_actions for p in alt) for alt in alternatives):
                    stale.add(f"{page.relative_to(ROOT)}: {command} {flag}")
    assert not stale, sorted(stale)


# ------------------------------------------------------------------ paths in backticks
SOURCE = (".py", ".md", ".json", ".sh", ".toml", ".txt", ".png", ".safetensors", ".cfg")
PLACEHOLDERS = ("runs/", "out/", "data/", "/")  # what a reader's commands make, not the repository
PATHLIKE = re.compile(r"^[\w.-]+(?:/[\w.-]*)+$|^[\w-]+\.(?:py|sh|toml|txt)$")
ATTRIBUTE = re.compile(r"^((?:[a-z_]+/)*[a-z_]+)\.([A-Za-z_][\w]*)$")  # `sim/constants.WORDS`


def repository_paths(page: Path) -> set[str]:
    """Backticked spans that name a repository file, folder or module (`sim/`, `tests/x.py`,
    `planning/tree.choose`), as written; paths a reader's commands make are left out."""
    found = set()
    for span in re.findall(r"(?<!`)`([^`\s]+)`(?!`)", page.read_text()):
        span = span.rstrip(".,:;")
        if span[0].isupper() or span.startswith(PLACEHOLDERS) and not span.startswith("data/") or "*" in span:
            continue  # RUN/..., W/..., runs/..., out/..., /shared/...
        if span.startswith("data/") and not (span.endswith(SOURCE) or span == "data/"):
            continue  # a dataset folder; `data/effects.py` is the package's
        if (
            PATHLIKE.match(span)
            and (span.endswith(SOURCE) or span.endswith("/"))
            or ATTRIBUTE.match(span)
            and "/" in span
        ):
            found.add(span)
    return found


def resolves(span: str, page: Path) -> bool:
    m = ATTRIBUTE.match(span)
    if m and not span.endswith(SOURCE):
        span = m.group(1) + ".py"
    roots = [ROOT, ROOT / "src" / "afford", page.parent, ROOT / "tests"]
    if "/" not in span:  # a bare name such as `test_physics.py`: somewhere in the repo
        return (ROOT / span).exists() or any(
            p.name == span for d in ("src", "tests", "scripts", "benchmarks") for p in (ROOT / d).rglob(span)
        )
    return any((r / span).exists() for r in roots)


def test_every_backticked_repository_path_exists():
    missing = sorted(
        f"{page.relative_to(ROOT)}: {span}"
        for page in PAGES
        for span in repository_paths(page)
        if not resolves(span, page)
    )
    assert not missing, missing


def test_the_staleness_checks_catch_a_planted_flag_and_path(tmp_path):
    page = tmp_path / "stale.md"
    page.write_text(
        "Plan with `afford plan --task T.json --planner learned --no-such-flag`, as `planning/guided.py`\n"
        "and `tests/test_cli.py` say; `afford bench tasks --planner all` and `planning/tree.py` are fine.\n"
    )
    stale = [
        (command, flag)
        for command, alternatives, flags in flags_beside_commands(page)
        for flag in flags
        if not all(any(flag in p._option_string_actions for p in alt) for alt in alternatives)
    ]
    assert stale == [("afford plan", "--no-such-flag")]
    missing = sorted(span for span in repository_paths(page) if not resolves(span, page))
    assert missing == ["planning/guided.py", "tests/test_cli.py"]


def test_the_architecture_page_shows_the_import_graph_as_it_is():
    run = subprocess.run(
        [sys.executable, str(ROOT / "scripts" / "import_graph.py")], capture_output=True, text=True
    )
    graph = re.search(r"```mermaid.*?```", run.stdout, re.S)
    assert graph and graph.group(0) in (ROOT / "docs" / "architecture.md").read_text(), (
        "docs/architecture.md's import graph is stale: paste the output of python scripts/import_graph.py"
    )


# ------------------------------------------------------------------ what is, not how it went
HISTORY = re.compile(
    r"\b(?:first|second|third|fourth|fifth|sixth|seventh|eighth|ninth|tenth|eleventh|twelfth|thirteenth"
    r"|fourteenth|this|that|next|last|same)[ -]session\b|\bissue \d+|\bissue's\b|\(issue\)",
    re.I,
)


def test_no_page_or_source_names_a_step_of_the_works_history():
    files = [*PAGES, ROOT / "Makefile"]
    for folder in ("src", "tests", "scripts", "benchmarks"):
        files += sorted((ROOT / folder).rglob("*.py"))
    found = [
        f"{f.relative_to(ROOT)}: {m.group(0)!r}"
        for f in files
        if f.name != "test_docs.py"
        for m in HISTORY.finditer(f.read_text())
    ]
    assert not found, found


# The pages say what is: words that tell how it was, beside the history words above. Pages
# only: the sources use some of them as the grammar's words ("no longer on the table"). Whole
# words ("known" is not "now"); "used to" after a form of "be" is a purpose ("is used to train").
PAGE_HISTORY = re.compile(
    r"\bnow\b|(?<!\bis )(?<!\bare )(?<!\bwas )(?<!\bwere )(?<!\bbe )(?<!\bbeen )\bused to\b"
    r"|\bno longer\b|\bshipped before\b",
    re.I,
)
DATE = re.compile(r"\b20\d\d-\d\d-\d\d\b")
COMMIT = re.compile(r"\bcommits? [0-9a-f]{7,40}\b")


def history_words(text: str) -> list[str]:
    return [m.group(0) for m in PAGE_HISTORY.finditer(text)]


def undated_dates(text: str) -> list[str]:
    """Dates in a paragraph that names no commit: a date belongs only beside the commit a
    measurement was recorded at."""
    return [d for para in re.split(r"\n\s*\n", text) if not COMMIT.search(para) for d in DATE.findall(para)]


def test_no_page_says_how_it_was():
    found = [
        f"{page.relative_to(ROOT)}: {word!r}"
        for page in PAGES
        for word in history_words(page.read_text()) + undated_dates(page.read_text())
    ]
    assert not found, found


def test_the_history_words_are_whole_words():
    planted = (
        "It now plans. It used to grow. It is no longer here. The net shipped before it. "
        "A known fix; nowhere; the snow. The data is used to train it. Measured 2026-12-01."
    )
    assert history_words(planted) == ["now", "used to", "no longer", "shipped before"]
    assert undated_dates(planted) == ["2026-12-01"]
    assert undated_dates("Recorded 2026-12-01 at commit 0fa098e.") == []


README_AND_DOCS_MAX_LINES = 3000


def test_the_readme_and_docs_are_a_read_one_finishes():
    lines = sum(len(page.read_text().splitlines()) for page in PAGES)
    assert lines <= README_AND_DOCS_MAX_LINES, (
        f"README.md and docs/ hold {lines} lines, over {README_AND_DOCS_MAX_LINES}: cut before adding"
    )


# ------------------------------------------------------------------ README's figures are the pages'
def section(page: Path, anchor: str) -> str:
    """The text under the heading with GitHub anchor `anchor`, up to the next one of its level or above."""
    lines = page.read_text().splitlines()
    for i, line in enumerate(lines):
        m = re.match(r"(#+) (.*)", line)
        if m and re.sub(r"[^\w\- ]", "", m.group(2).lower()).replace(" ", "-") == anchor:
            level, body = len(m.group(1)), []
            for rest in lines[i + 1 :]:
                h = re.match(r"(#+) ", rest)
                if h and len(h.group(1)) <= level:
                    break
                body.append(rest)
            return "\n".join(body)
    raise AssertionError(f"{page.name} has no heading for #{anchor}")


FIGURE = re.compile(r"-?\d+(?:\.\d+)?(?:/\d+)+%?|-?\d+\.\d+%?")


def test_every_figure_in_the_readme_results_table_is_on_the_page_it_links_to():
    readme = (ROOT / "README.md").read_text()
    table = readme[readme.index("## Results against the paper") :].split("\n\n")[2]
    rows = [r for r in table.splitlines() if r.startswith("| [")]
    assert len(rows) >= 10
    squeeze = lambda text: re.sub(r"\s*/\s*", "/", text.replace("*", ""))  # noqa: E731
    for row in rows:
        link, _, here = [c.strip() for c in row.strip("|").split("|")]
        target = re.search(r"\]\(([^)#]+)#([^)]+)\)", link)
        page = squeeze(section(ROOT / target.group(1), target.group(2)))
        missing = [f for f in FIGURE.findall(squeeze(here)) if f not in page]
        assert not missing, f"README row {link[:40]}...: {missing} not on {target.group(1)}#{target.group(2)}"
