"""A plan you can look into: one self-contained HTML page of the search tree (paper Fig. 5).

Every state the planner grew is a node: its (predicted) image with the affordances recognised
on it drawn, the action that led to it, and its eq. (5) loss against the goal patch. The
chosen plan's path is marked and open; the rest folds and unfolds (HTML `details`), and a
click on a node shows its image large beside the tree. A closed-loop run (planning/
closed_loop.py) is one tree per round, with the state observed after each round's action
between them. Images are inlined as JPEG data, so the page is one file with no requests.
"""

from __future__ import annotations

import base64
import html
import io
from pathlib import Path

from afford.viz.draw import draw_affordances, to_pil
from afford.viz.plan import action_text, goal_panel

SCALE = 2  # pixels per image pixel in the page (128 x 128 states shown at 256)
QUALITY = 80  # JPEG: a 4-step tree of ~700 states stays a few MB

STYLE = """
body { font: 14px sans-serif; margin: 0; display: flex; }
#tree { flex: 1; padding: 12px; overflow: auto; height: 100vh; box-sizing: border-box; }
#view { width: 300px; padding: 12px; border-left: 1px solid #ccc; position: sticky; top: 0; height: 100vh; }
#view img { width: 256px; image-rendering: pixelated; }
details { margin-left: 18px; }
summary { cursor: pointer; padding: 1px 0; }
summary img { width: 40px; height: 40px; vertical-align: middle; margin-right: 6px; }
.chosen > summary { font-weight: bold; background: #e4f4e4; }
.loss { color: #666; font-family: monospace; }
.observed { margin: 12px 0; padding: 8px; background: #eef; }
.observed img { width: 128px; vertical-align: middle; }
"""

SCRIPT = """
function show(s) {
  const v = document.getElementById('view');
  v.querySelector('img').src = s.querySelector('img').src;
  v.querySelector('p').textContent = s.dataset.info;
}
document.querySelectorAll('summary[data-node]').forEach(s => s.addEventListener('click', () => show(s)));
// page.html#state-K opens with state K of the first tree shown (links, screenshots)
const asked = location.hash.match(/^#state-(\\d+)$/);
if (asked) { const s = document.querySelector(`summary[data-node="${asked[1]}"]`); if (s) show(s); }
"""


def data_uri(pil) -> str:
    buf = io.BytesIO()
    pil.convert("RGB").save(buf, "JPEG", quality=QUALITY)
    return "data:image/jpeg;base64," + base64.b64encode(buf.getvalue()).decode("ascii")


def node_label(node) -> str:
    if not node.plan:
        return "start"
    a = node.plan[-1]
    return action_text(a) + f" at ({a.position[0]:.2f}, {a.position[1]:.2f})"


def node_info(node, index: int) -> str:
    found = "not expanded" if node.recognised is None else f"{len(node.recognised)} affordances recognised"
    types = ""
    if node.recognised:
        counts: dict[str, int] = {}
        for d in node.recognised:
            counts[d.affordance.type] = counts.get(d.affordance.type, 0) + 1
        types = " (" + ", ".join(f"{n} {t}" for t, n in sorted(counts.items())) + ")"
    return (
        f"state {index}, depth {node.depth}: {node_label(node)}; eq. (5) loss {node.loss:.5f}; {found}{types}"
    )


def tree_html(result, name: str) -> str:
    """One tree (a planning `SearchResult`) as nested `details`, the chosen path open and marked."""
    children: dict[int, list[int]] = {}
    for i, n in enumerate(result.nodes):
        if n.parent >= 0:
            children.setdefault(n.parent, []).append(i)
    chosen = set()
    i = result.best
    while i >= 0:
        chosen.add(i)
        i = result.nodes[i].parent

    def render(i: int) -> str:
        n = result.nodes[i]
        pil = to_pil(n.image, SCALE)
        if n.recognised:
            pil = draw_affordances(pil, [d.affordance for d in n.recognised], SCALE)
        info = html.escape(node_info(n, i), quote=True)
        mark = ' class="chosen"' if i in chosen else ""
        opened = " open" if i in chosen or n.depth == 0 else ""
        inner = "".join(render(k) for k in children.get(i, []))
        return (
            f'<details{mark}{opened} data-node="{i}"><summary data-node="{i}" data-info="{info}">'
            f'<img src="{data_uri(pil)}" alt="state {i}">{html.escape(node_label(n))} '
            f'<span class="loss">{n.loss:.5f}</span></summary>{inner}</details>'
        )

    head = f"<h3>{html.escape(name)}: {len(result.nodes)} states, plan of {len(result.plan)} steps</h3>"
    return f'<div class="tree">{head}{render(0)}</div>'


def report_html(outcome, goal) -> str:
    """The page for a planning `Outcome` (planning/run.py): its tree, or a closed loop's trees."""
    size = outcome.planned[0].shape[0]
    verdict = "solved" if outcome.success else "failed"
    plan = " > ".join(action_text(a) for a in outcome.plan or ()) or "(none)"
    parts = [
        f"<h2>{html.escape(outcome.task)}: {html.escape(outcome.planner)}, {verdict}</h2>",
        f"<p>plan: {html.escape(plan)}; {outcome.nodes} states, {outcome.seconds:.1f} s planning</p>",
        f"<p>goal{' (NOT)' if goal.negative else ''}: "
        f'<img src="{data_uri(goal_panel(goal.patch, size, goal.negative, SCALE))}" width="128"></p>',
    ]
    loop = getattr(outcome, "loop", None)
    if loop is not None:
        for k, step in enumerate(loop.steps, 1):
            parts.append(tree_html(step.search, f"round {k}"))
            parts.append(
                f'<div class="observed">observed after round {k} ({html.escape(action_text(step.action))}; '
                f"eq. (5) between foreseen and observed {step.gap:.5f}): "
                f'<img src="{data_uri(to_pil(step.predicted, 1))}" title="foreseen"> '
                f'<img src="{data_uri(to_pil(step.observed, 1))}" title="observed"></div>'
            )
        if loop.last is not None:
            parts.append(tree_html(loop.last, f"round {len(loop.steps) + 1} (the empty plan: done)"))
    elif outcome.search is not None:
        parts.append(tree_html(outcome.search, "search tree"))
    else:
        parts.append(
            "<p>This planner grows no tree of states (the symbolic planner searches canonical facts).</p>"
        )
    view = '<div id="view"><img alt=""><p>Click a state to see it here.</p></div>'
    return (
        "<!DOCTYPE html><html><head><meta charset='utf-8'>"
        f"<title>{html.escape(outcome.task)} ({html.escape(outcome.planner)})</title>"
        f"<style>{STYLE}</style></head>"
        f'<body><div id="tree">{"".join(parts)}</div>{view}<script>{SCRIPT}</script></body></html>'
    )


def write_report(outcome, goal, path: str | Path) -> Path:
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(report_html(outcome, goal), encoding="utf-8")
    return path
