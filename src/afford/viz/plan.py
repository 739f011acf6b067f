"""Plan pictures in the style of the paper's Fig. 8: goal | start | planned states, each with
the affordance executed from it drawn | the executed result."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from PIL import Image, ImageDraw

from afford.viz.draw import SCALE, depth_pil, draw_affordances, hstack, label, to_pil, vstack


def goal_panel(patch: np.ndarray, size: int, negative: bool, scale: int = SCALE) -> Image.Image:
    """The goal patch at the same scale as the states, centred on a grey panel; a negative
    goal is crossed out (paper: "NOT")."""
    panel = Image.new("RGB", (size * scale, size * scale), (200, 200, 200))
    p = to_pil(patch, scale)
    x, y = (panel.width - p.width) // 2, (panel.height - p.height) // 2
    panel.paste(p, (x, y))
    if patch.shape[2] == 4:
        d = depth_pil(patch, scale)
        d = d.resize((d.width // 2, d.height // 2))
        panel.paste(d, (panel.width - d.width - 2, panel.height - d.height - 2))
    if negative:
        draw = ImageDraw.Draw(panel)
        draw.line([(x, y), (x + p.width, y + p.height)], fill=(255, 0, 0), width=3)
        draw.line([(x, y + p.height), (x + p.width, y)], fill=(255, 0, 0), width=3)
    return panel


def action_text(a) -> str:
    """An affordance as pictures and reports name it: its type, and a turn's angle."""
    return a.type + (f" {a.turn:+g}" if a.turn else "")


def loop_picture(outcome, goal, path: str | Path) -> None:
    """A closed-loop run (planning/closed_loop.py): above, the state each round's plan foresaw
    after its first action; below, the state observed, with the next round's action drawn."""
    loop = outcome.loop
    size = loop.start.shape[0]
    kind = "NOT " if goal.negative else ""
    top = [label(goal_panel(goal.patch, size, goal.negative), f"goal: {kind}{goal.channels.upper()}")]
    first = to_pil(loop.start)
    if loop.steps:
        first = draw_affordances(first, [loop.steps[0].action])
    bottom = [
        label(first, "start" + (f": {action_text(loop.steps[0].action)}" if loop.steps else " (no plan)"))
    ]
    for i, step in enumerate(loop.steps, 1):
        top.append(label(to_pil(step.predicted), f"foreseen {i} (gap {step.gap:.5f})"))
        seen = to_pil(step.observed)
        if i < len(loop.steps):
            nxt = loop.steps[i].action
            seen = draw_affordances(seen, [nxt])
            text = f"observed {i}: {action_text(nxt)}"
        else:
            text = f"observed {i}: {'solved' if outcome.success else 'FAILED'}"
        bottom.append(label(seen, text))
    picture = vstack([hstack(top), hstack(bottom)])
    stopped = "the plan came back empty" if loop.stopped == "goal" else "the steps were spent"
    Path(path).parent.mkdir(parents=True, exist_ok=True)
    label(picture, f"{outcome.task} | {outcome.planner}, closed loop: {stopped}").save(path)


def plan_strip(outcome, goal, path: str | Path) -> None:
    """Write the Fig. 8-style strip for a planning `Outcome` (a closed-loop one: `loop_picture`)."""
    if getattr(outcome, "loop", None) is not None:
        loop_picture(outcome, goal, path)
        return
    size = outcome.planned[0].shape[0]
    kind = "NOT " if goal.negative else ""
    panels = [label(goal_panel(goal.patch, size, goal.negative), f"goal: {kind}{goal.channels.upper()}")]
    plan = outcome.plan or ()
    for i, image in enumerate(outcome.planned):
        pil = to_pil(image)
        if i < len(plan):
            a = plan[i]
            pil = draw_affordances(pil, [a])
            text = f"{'start' if i == 0 else f'planned {i}'}: {a.type}" + (f" {a.turn:+g}" if a.turn else "")
        else:
            text = "start (no plan)" if i == 0 and not plan else f"planned {i}"
        panels.append(label(pil, text))
    verdict = "solved" if outcome.success else "FAILED"
    if outcome.perturbed:
        verdict += f"; perturbed {sum(outcome.perturbed)}/{len(outcome.perturbed)}"
    panels.append(label(to_pil(outcome.executed[-1]), f"executed: {verdict}"))
    strip = hstack(panels)
    title = f"{outcome.task} | {outcome.planner}"
    Path(path).parent.mkdir(parents=True, exist_ok=True)
    label(strip, title).save(path)
