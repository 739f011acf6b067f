"""What a goal sentence reads to: clauses over facts, and the error for one that cannot be read.

The records every reader and writer of sentences shares (`sentences.py` writes and samples
them, `reference.py` builds them from a parsed sentence, the agreement model and the success
predicate judge them), kept apart so that none of those modules has to import another.
"""

from __future__ import annotations

from dataclasses import dataclass

from afford.errors import UserError
from afford.words.facts import Fact, State


class SentenceError(UserError):
    """A sentence that cannot be read: one line naming the word or part that failed and, where
    one is found, a reading that can."""


@dataclass(frozen=True)
class Clause:
    fact: Fact
    negated: bool = False

    def holds(self, state: State) -> bool:
        return self.fact.holds(state) != self.negated


@dataclass(frozen=True)
class Statement:
    """Clauses joined by "and"; `text` as the agreement model reads it: the sentence as
    written where it is in the phrasings the model was taught, else its clauses written in
    them (`sentences.parse`)."""

    clauses: tuple[Clause, ...]
    text: str

    def holds(self, state: State) -> bool:
        return all(c.holds(state) for c in self.clauses)
