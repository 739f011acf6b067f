"""What a goal sentence reads to: clauses over facts, the error for one that cannot be read,
and a parse's records before the scene resolves them (`Noun`, `Pred`, `Item`).

The records every reader and writer of sentences shares (`sentences.py` writes and samples
them, `reference.py` builds them from a parsed sentence, the agreement model and the success
predicate judge them), kept apart so that none of those modules has to import another.
"""

from __future__ import annotations

from dataclasses import dataclass

from afford.errors import UserError
from afford.words.facts import Fact, State


class Unread(Exception):
    """A sentence the grammar cannot read: the reason, its words, and the index of the word
    where it failed (None: at the end, or nowhere in particular)."""

    def __init__(self, reason: str, words: list[str], at: int | None) -> None:
        super().__init__(reason)
        self.reason, self.words, self.at = reason, words, at


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


# ---------------------------------------------------------------------------- a parse, unresolved
@dataclass(frozen=True)
class Noun:
    """A noun phrase as said, before it is resolved against a scene.

    words: as written, for messages; kind: a key of the scene's kinds, or None (a pronoun,
    "the red one"); quantity: "one" ("the cup"), "some" ("a cup"), "every" ("all cups", "the
    cups"), "both", "two"/"three" ("the two cups"), "none" ("no cup"), "it", "them",
    "everything"; denied: the clauses about it are negated ("neither the cup nor the ball",
    "no cup"); colour and order words; restrict: relations it must stand in on the start
    scene ("the cup left of the ball", "the cup that is upright"); bare: nothing rests on it ("the
    empty support"); other: not the objects said before it nor what its subject rests on ("the
    other support"); excluded: the objects it leaves out ("every cup except the middle one");
    bears: what rests on it ("the support the ball is on"); quantity "host": what the noun of
    `bears` rests on at the start, the table included ("where the ball was"); owner: whose it
    is ("its post", "the ball's post": what rests on the owner at the start or what it rests
    on; a pronoun's owner is found by the clause, `reference.py`)."""

    words: str
    kind: str | None
    quantity: str
    colour: str | None = None
    order: tuple[str, ...] = ()
    from_right: bool = False
    restrict: tuple[Pred, ...] = ()
    nearest: tuple[Noun, ...] = ()
    farthest: tuple[Noun, ...] = ()  # "the cup farther from the ball"
    denied: bool = False
    bare: bool = False
    other: bool = False
    excluded: tuple[Noun, ...] = ()
    bears: tuple[Noun, ...] = ()
    owner: tuple[Noun, ...] = ()


@dataclass(frozen=True)
class Pred:
    """One relation said of a subject: its name (a key of facts.RELATIONS), its other argument
    (the nouns of a list, a word such as "table" or "left", or None) and whether it is negated.
    host: the block an end belongs to ("the left end of the block"); implied: said by a verb
    ("stands on" implies upright) and dropped where the subject cannot take it; passing: held
    on the way ("pick up the cup and put it on the block"), dropped when a later clause of the
    sentence puts its subject somewhere; source: where the subject starts ("from the support"),
    its name read as what the subject rests on where it names several."""

    relation: str
    other: tuple[Noun, ...] | str | None = None
    negated: bool = False
    host: tuple[Noun, ...] = ()
    implied: bool = False
    passing: bool = False
    source: bool = False


@dataclass(frozen=True)
class Item:
    """One thing the goal asks: its subjects and what is said of them (preds None: what was
    said in the item before, "and so is the cup"); instruction: said as an order ("put ...");
    explained: said before a colon, its pronouns naming what the items after it name ("swap
    them: the ball on the block and the cup on the support")."""

    subjects: tuple[Noun, ...]
    preds: tuple[Pred, ...] | None
    instruction: bool = False
    explained: bool = False
