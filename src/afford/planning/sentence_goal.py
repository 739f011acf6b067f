"""Goals in words (paper V): eq. (4) over the agreement model's score in place of eq. (5).

Paper V finds image goals "impractical in practice" and proposes a network that "quantifies
agreement between predicted outcomes and sentences describing goals". A `SentenceGoal` is
read against the task's start scene (every word known, every name an object of it:
`words/sentences.parse`), and the loss of a (predicted) state is minus the log-probability the
agreement model gives that every clause holds in it, so eq. (4)'s argmin picks the plan whose
end the sentence describes best. The same loss scores the oracle's true leaves and the learned
world model's predictions. Success, where a task gives no predicate, is the statement judged on
the true poses after execution (`words/facts.py`).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from afford.planning.goal import GoalError
from afford.shipped import Nets, NetsError
from afford.words.facts import State
from afford.words.sentences import Statement

PANEL_WIDTH = 128  # px: the sentence drawn where pictures show an image goal


def load_agreement(weights=None):
    """The agreement model of a weights folder's bundle (default: the package's)."""
    return _agreement(Nets(weights))


def _agreement(nets: Nets):
    try:
        return nets.agreement
    except NetsError as e:
        raise GoalError(
            f"no agreement model for goals in words: {e}; train one with `afford train goals` and "
            "export it there with `afford weights export agreement.safetensors`"
        ) from None


@dataclass
class SentenceGoal:
    statement: Statement
    negative: bool = False  # a sentence says what should hold; negation is written in it
    # The bundle whose agreement model scores the sentence, the planner's (None: the package's,
    # made on the first score).
    nets: Nets | None = field(default=None, repr=False, compare=False)

    channels = "text"

    @property
    def text(self) -> str:
        return self.statement.text

    @property
    def net(self):
        if self.nets is None:
            self.nets = Nets()
        return _agreement(self.nets)

    def loss_torch(self, states):
        """-log P(the sentence holds) for torch states (B, C, H, W): eq. (4) minimises it."""
        return -self.net.statement_logprob(states, self.text)

    def loss(self, states: np.ndarray) -> np.ndarray:
        """For a batch of states (B, H, W, 4) -> (B,)."""
        import torch

        from afford.images import to_chw

        images = to_chw(np.asarray(states, dtype=np.float32))
        with torch.no_grad():
            parts = [self.loss_torch(images[i : i + 64]).numpy() for i in range(0, len(images), 64)]
        return np.concatenate(parts).astype(np.float64) if parts else np.zeros(0)

    def best(self, losses: np.ndarray) -> int:
        return int(np.argmin(losses))

    @property
    def patch(self) -> np.ndarray:
        """The sentence drawn black on white (RGB), for pictures of the plan."""
        from afford.viz.draw import text_patch

        return text_patch(self.text, PANEL_WIDTH)


@dataclass(frozen=True)
class StatementHolds:
    """A task's success as a predicate: the statement on the true poses of the scene."""

    statement: Statement
    members: frozenset[int]

    def holds(self, scene, see: bool = True) -> bool:
        return self.statement.holds(State.of_scene(scene, self.members))

    def describe(self) -> str:
        return self.statement.text

    def objects(self) -> set[str]:
        return set()
