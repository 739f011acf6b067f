"""The symbolic planner's outcome: its canonical plan executed in the simulator and judged, and
where physics put the objects other than the canonical effects said."""

from __future__ import annotations

import numpy as np

from afford.planning.judge import execute_plan
from afford.planning.outcome import Outcome
from afford.planning.symbolic import CanonicalWorld, plan_symbolic
from afford.planning.tasks import Task
from afford.sim.constants import TOLERANCES
from afford.sim.scene import Scene

DEVIATION = TOLERANCES.position  # this far from its canonical place, an object's fate is non-canonical


def solve_symbolic(task: Task, scene: Scene) -> Outcome:
    """The symbolic planner's outcome: its plan executed and judged, the others of equal length
    executed too (the share that succeed), and where physics differed from canonical effects."""
    names = task.object_names()
    result = plan_symbolic(scene, task.scene, names, task.success, task.max_steps)
    if result.plan is None:
        scene.reset(task.scene)
        start = scene.observe()
        return Outcome(
            task=task.name,
            planner="symbolic",
            plan=None,
            planned=[start],
            executed=[start],
            success=False,
            nodes=result.expanded,
            seconds=result.seconds,
            reason=f"no plan of at most {task.max_steps} steps reaches the goal by canonical effects",
            success_rate=0.0,
        )
    world = CanonicalWorld(scene, task.scene, names)
    planned = []
    for state in result.trace:
        world.realise(state)
        planned.append(scene.observe())
    # The others first, so that the scene ends on the plan the outcome reports.
    others = [execute_plan(scene, task.scene, plan, task.success).success for plan in result.plans[1:]]
    ex = execute_plan(scene, task.scene, result.plan, task.success)
    reason = "" if ex.success else deviation(scene, result.predicted, names)
    rate = (ex.success + sum(others)) / len(result.plans)
    if len(result.plans) > 1:
        reason = (reason + "; " if reason else "") + (
            f"{rate:.0%} of {len(result.plans)} equally short canonical plans succeed"
            + (f" (sampled from {result.total})" if result.total > len(result.plans) else "")
        )
    return Outcome(
        task=task.name,
        planner="symbolic",
        plan=result.plan,
        planned=planned,
        executed=ex.images,
        success=ex.success,
        nodes=result.expanded,
        seconds=result.seconds,
        reason=reason,
        steps_executed=ex.executed,
        success_rate=rate,
        tried=len(result.plans),
        total=result.total,
    )


def deviation(scene: Scene, predicted, names: list[str]) -> str:
    """Which objects physics put somewhere other than the canonical effects said."""
    notes = []
    for name in names:
        real = scene.object(name)
        want = np.asarray(predicted.pose(name).pos)
        if not real.present:
            notes.append(f"{name} fell off the table")
            continue
        off = float(np.linalg.norm(real.pos - want))
        if off > DEVIATION and name != predicted.held:
            tipped = " and toppled" if real.kind == "cup" and real.up_axis[2] < TOLERANCES.upright_cos else ""
            notes.append(f"{name} ended {off * 100:.0f} cm from its canonical place{tipped}")
    detail = "; ".join(notes) if notes else "objects are where canonical effects put them"
    return f"non-canonical effects: {detail}"
