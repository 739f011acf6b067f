"""Why a learned plan failed: the oracle's plan replayed through the learned world model
(the EM*D nets', or the object world model's: `planner`).

The oracle (the simulator as world model) gives a plan that works. Replaying it step by step
through the learned model says at which depth of the method the learned planner lost it:

- execution: a step of the chosen plan could not be carried out in the simulator: an
  affordance recognised on a predicted state is not there (position or angle off);
- recognition: at some step, no edge the learned planner grows on its own predicted state
  matches the oracle's action (Table 1's criteria), so the working plan is not in its tree;
- goal: the oracle's plan is in the tree, and the chosen plan truly scores at least as well
  against the goal (eq. 5) yet fails the success predicate: the goal image does not tell the
  two apart, and no world model would help;
- prediction: the oracle's plan is in the tree and truly scores better, but the net's
  prediction of it scored worse than the chosen plan: the net foresaw the effects wrongly.

With the oracle's own plan failing, the task cannot be diagnosed this way ("oracle fails").
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from afford.metrics import matches
from afford.planning.run import WORLD_MODELS, Outcome, PlannerConfig, solve
from afford.planning.tasks import Task
from afford.planning.tree import Node, SearchConfig, edges
from afford.shipped import Nets
from afford.sim.scene import Scene

CAUSES = ("solved", "oracle fails", "execution", "recognition", "goal", "prediction")
PLANNERS = tuple(WORLD_MODELS)  # the planners with a learned world model to replay through


@dataclass
class StepCheck:
    """One step of the oracle's plan on the learned model's predicted states."""

    action: str
    recognised: bool  # an edge on the predicted state matches the oracle's action
    nearest_cm: float | None  # the nearest edge of its type (and turn), centimetres
    predicted_loss: float  # eq. (5) on the learned prediction after this step
    true_loss: float  # eq. (5) on the simulator's state after this step


@dataclass
class Diagnosis:
    task: str
    cause: str
    learned: Outcome
    oracle: Outcome | None  # None when the learned plan succeeded
    steps: list[StepCheck] = field(default_factory=list)
    chosen_true_loss: float | None = None  # eq. (5) on the executed learned plan's end state
    planner: str = "learned"

    def to_dict(self) -> dict:
        return {
            "task": self.task,
            "planner": self.planner,
            "cause": self.cause,
            "learned_plan": [a.to_dict() for a in self.learned.plan or ()],
            "learned_predicted_loss": self.learned.loss,
            "learned_true_loss": self.chosen_true_loss,
            "oracle_plan": [a.to_dict() for a in self.oracle.plan or ()] if self.oracle else None,
            "oracle_steps": [vars(s) for s in self.steps],
        }

    def describe(self) -> str:
        lines = [f"{self.task}: {self.cause}"]
        for i, s in enumerate(self.steps, 1):
            near = "none of its type" if s.nearest_cm is None else f"nearest {s.nearest_cm:.1f} cm"
            lines.append(
                f"  oracle step {i} {s.action}: {'in the tree' if s.recognised else 'NOT recognised'} "
                f"({near}); loss predicted {s.predicted_loss:.5f}, true {s.true_loss:.5f}"
            )
        if self.learned.plan is not None and self.chosen_true_loss is not None:
            lines.append(
                f"  {self.planner} chose {len(self.learned.plan)} steps: loss predicted "
                f"{self.learned.loss:.5f}, true {self.chosen_true_loss:.5f}"
            )
        return "\n".join(lines)


def diagnose(
    task: Task, scene: Scene, nets: Nets, config: PlannerConfig | None = None, planner: str = "learned"
) -> Diagnosis:
    """Plan `task` with `planner` (one of PLANNERS) and the oracle, then replay the oracle's
    plan through the planner's world model to name the cause of a failure (module docstring)."""
    if planner not in PLANNERS:
        raise ValueError(f"diagnose: planner {planner!r}; expected one of {', '.join(PLANNERS)}")
    config = config or PlannerConfig(search=SearchConfig(progress=False))
    mine = solve(task, planner, scene, config, nets)
    chosen_true = float(task.goal.loss(mine.executed[-1][None])[0])
    if mine.success:  # nothing to explain, and no oracle tree to grow
        return Diagnosis(task.name, "solved", mine, None, chosen_true_loss=chosen_true, planner=planner)
    oracle = solve(task, "oracle", scene, config)
    if not oracle.success:
        return Diagnosis(task.name, "oracle fails", mine, oracle, [], chosen_true, planner)
    # The oracle's run already holds every true state of its plan, the start first: the replay
    # starts from that start image and needs the simulator no more.
    truth = oracle.executed
    model = WORLD_MODELS[planner](scene, truth[0], config, nets)
    image, state = model.root()
    node = Node((), image, state)
    steps = []
    for i, action in enumerate(oracle.plan):
        found = edges(model.recognise([node])[0], config.search.merge_radius)
        same = [e for e in found if e.type == action.type and e.turn == action.turn]
        near = min(
            (float(np.linalg.norm(np.subtract(e.position, action.position))) for e in same), default=None
        )
        ((image, state),) = model.predict([node], [action])
        node = Node(node.plan + (action,), image, state)
        steps.append(
            StepCheck(
                action.type + (f"{action.turn:+g}" if action.turn else ""),
                any(matches(e, action) for e in same),
                None if near is None else near * 100,
                float(task.goal.loss(image[None])[0]),
                float(task.goal.loss(truth[i + 1][None])[0]),
            )
        )
    sign = -1.0 if task.goal.negative else 1.0  # lower is better after this
    if not all(mine.steps_executed):
        cause = "execution"
    elif not all(s.recognised for s in steps):
        cause = "recognition"
    elif sign * chosen_true <= sign * steps[-1].true_loss:
        cause = "goal"
    else:
        cause = "prediction"
    return Diagnosis(task.name, cause, mine, oracle, steps, chosen_true, planner)
