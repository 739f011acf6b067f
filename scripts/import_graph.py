"""The package's import graph: its layers, and any import circle or import that runs up them.

    python scripts/import_graph.py            # the check, and the layer graph as Mermaid
    python scripts/import_graph.py --modules  # every module-to-module import, one a line

Every `import afford...` counts, also those inside functions (they hide circles rather than
remove them). Exit status 1 when a circle or an upward import is found; tests/test_structure.py
runs the same check.
"""

from __future__ import annotations

import argparse
import ast
import sys
from pathlib import Path

SRC = Path(__file__).resolve().parent.parent / "src"
# Lower layers first: a module may import from its own layer and the ones before it.
LAYERS = (
    ("afford", "afford.sim"),
    ("afford.data", "afford.training", "afford.viz"),
    ("afford.recognition", "afford.prediction", "afford.words", "afford.objects", "afford.shipped"),
    ("afford.planning",),
    ("afford.cli",),
)


def module_name(path: Path, src: Path = SRC) -> str:
    parts = path.relative_to(src).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def imports(path: Path, modules: set[str], src: Path = SRC) -> set[str]:
    """The package modules that the file at `path` imports, anywhere in it."""
    me = module_name(path, src)
    package = me if path.name == "__init__.py" else me.rpartition(".")[0]
    found: set[str] = set()
    for node in ast.walk(ast.parse(path.read_text())):
        names: list[str] = []
        if isinstance(node, ast.Import):
            names = [a.name for a in node.names]
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                base = ".".join(
                    package.split(".")[: len(package.split(".")) - node.level + 1] + ([base] if base else [])
                )
            names = [f"{base}.{a.name}" for a in node.names] + [base]
        for name in names:
            while name and name not in modules:
                name = name.rpartition(".")[0]
            if name and name != me and name != "afford":
                found.add(name)
    return found


def graph(src: Path = SRC) -> dict[str, set[str]]:
    files = {module_name(p, src): p for p in (src / "afford").rglob("*.py")}
    return {m: imports(p, set(files), src) for m, p in sorted(files.items())}


def layer_of(module: str) -> int:
    best, rank = -1, 0
    for k, layer in enumerate(LAYERS):
        for prefix in layer:
            if (module == prefix or module.startswith(prefix + ".")) and len(prefix) > best:
                best, rank = len(prefix), k
    return rank


def cycles(g: dict[str, set[str]]) -> list[list[str]]:
    """Strongly connected groups of more than one module (Tarjan)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on: set[str] = set()
    out: list[list[str]] = []

    def visit(v: str) -> None:
        index[v] = low[v] = len(index)
        stack.append(v)
        on.add(v)
        for w in g.get(v, ()):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            group = []
            while True:
                w = stack.pop()
                on.discard(w)
                group.append(w)
                if w == v:
                    break
            if len(group) > 1:
                out.append(sorted(group))

    sys.setrecursionlimit(10_000)
    for v in g:
        if v not in index:
            visit(v)
    return out


def upward(g: dict[str, set[str]]) -> list[tuple[str, str]]:
    return [(a, b) for a, deps in g.items() for b in sorted(deps) if layer_of(b) > layer_of(a)]


def package_of(module: str) -> str:
    parts = module.split(".")
    return ".".join(parts[:2]) if len(parts) > 1 else module


def mermaid(g: dict[str, set[str]]) -> str:
    edges = sorted({(package_of(a), package_of(b)) for a, deps in g.items() for b in deps})
    lines = ["flowchart BT"]
    lines += [f"    {a.replace('.', '_')}[{a}] --> {b.replace('.', '_')}[{b}]" for a, b in edges if a != b]
    return "\n".join(lines)


def main() -> int:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("--modules", action="store_true", help="list every module-to-module import")
    args = parser.parse_args()
    g = graph()
    if args.modules:
        for a, deps in g.items():
            for b in sorted(deps):
                print(f"{a} -> {b}")
        return 0
    circles, up = cycles(g), upward(g)
    print(f"{len(g)} modules, {sum(map(len, g.values()))} imports")
    for group in circles:
        print("import circle: " + " <-> ".join(group))
    for a, b in up:
        print(f"upward import: {a} (layer {layer_of(a)}) imports {b} (layer {layer_of(b)})")
    print("\n```mermaid\n" + mermaid(g) + "\n```")
    return 1 if circles or up else 0


if __name__ == "__main__":
    sys.exit(main())
