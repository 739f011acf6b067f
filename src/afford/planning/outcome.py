"""What a planner is told and what it gives back: `PlannerConfig` and `Outcome` (planning/run.py)."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from afford.planning.closed_loop import Loop
from afford.planning.hybrid import ACCEPT
from afford.planning.tree import SearchConfig, SearchResult
from afford.sim.affordances import Affordance


@dataclass(frozen=True)
class PlannerConfig:
    """How a planner plans: the tree search's settings, and each planner's own."""

    search: SearchConfig = field(default_factory=SearchConfig)
    # Hybrid planners (planning/hybrid.py): the share of the start's eq. (5) loss a canonical
    # plan's predicted outcome must remove to be kept.
    accept: float = ACCEPT
    # The learned planner: optimise the turn angles of the best plan with turns by gradient
    # descent through the prediction net (planning/angles.py) and keep it when it is closer.
    optimise_turns: bool = False
    # The learned and object planners with outcomes "expected" (planning/branches.py): a plan
    # scores eq. (5) averaged over the branches of the outcomes foreseen, plus this many
    # standard deviations of it (risk-averse); 0: the mean alone.
    risk: float = 1.0
    # Plan, execute the first action, look at the real state, plan again with the steps left
    # (planning/closed_loop.py); False: the paper's open loop, the whole plan executed blind.
    closed_loop: bool = False
    # The learned planners, with a net that foresees several outcomes per step: "likeliest",
    # each step carries on the one its head finds likeliest; "expected", every outcome is kept
    # as a branch and a plan scores its expected eq. (5) (planning/branches.py).
    outcomes: str = "likeliest"


@dataclass
class Outcome:
    task: str
    planner: str
    plan: tuple[Affordance, ...] | None
    planned: list[np.ndarray]  # the planner's view of each state, the start first
    executed: list[np.ndarray]  # the simulator's, after executing the plan
    success: bool
    nodes: int  # states the planner generated
    seconds: float
    loss: float | None = None
    reason: str = ""
    steps_executed: list[bool] = field(default_factory=list)
    # Symbolic only: of its equally short canonical plans (`tried` executed of `total`), the
    # share that succeed. `success` is the first of them, a seeded random tie-break.
    success_rate: float | None = None
    tried: int = 0
    total: int = 0
    truncated: bool = False  # the search's time limit stopped the tree early
    source: str = ""  # hybrid only: "symbolic" (a checked canonical plan) or "fallback" (the search)
    # `execute_perturbed`: the plan's success in each execution from a perturbed start.
    perturbed: list[bool] = field(default_factory=list)
    loop: Loop | None = None  # closed loop only: each round's plan, prediction and observation
    search: SearchResult | None = None  # the tree the plan was chosen from (reports; not in to_dict)

    def to_dict(self) -> dict:
        fair = {}
        if self.success_rate is not None:
            fair = {
                "success_rate": round(self.success_rate, 4),
                "plans_tried": self.tried,
                "plans_total": self.total,
            }
        return (
            fair
            | {
                "task": self.task,
                "planner": self.planner,
                "solved": self.success,
                "plan": None if self.plan is None else [a.to_dict() for a in self.plan],
                "plan_length": None if self.plan is None else len(self.plan),
                "nodes": self.nodes,
                "planning_seconds": round(self.seconds, 2),
                "goal_loss": None if self.loss is None else round(self.loss, 6),
                "reason": self.reason,
            }
            | ({"truncated": True} if self.truncated else {})
            | ({"source": self.source} if self.source else {})
            | (
                {
                    "closed_loop": {
                        "stopped": self.loop.stopped,
                        "rounds": [s.to_dict() for s in self.loop.steps],
                    }
                }
                if self.loop is not None
                else {}
            )
            | (
                {
                    "perturbed_executions": len(self.perturbed),
                    "perturbed_success_rate": round(sum(self.perturbed) / len(self.perturbed), 4),
                }
                if self.perturbed
                else {}
            )
        )
