"""Sentences about states: written from facts, sampled true or false, and read back.

A statement is one or more clauses joined by "and", each a fact (`words/facts.py`) or its
negation, written in one of several phrasings so that a model learns the relation and not a
template. Objects are named by kind ("the cup"), by colour ("the blue cup"), and, where the
scene holds several of a kind, by their order from the camera's left ("the left support").

`parse` reads a sentence back into clauses against a state (a task's start scene): a word
outside the vocabulary, a clause in no known phrasing, or a name that fits no object is a
`SentenceError` naming what it could not read.
"""

from __future__ import annotations

import functools
import re
from dataclasses import dataclass

import numpy as np

from afford.errors import UserError
from afford.sim.constants import WORDS
from afford.words.facts import RELATION_NAMES, RELATIONS, Fact, State

COLOURS = {"cup": "blue", "ball": "red", "support": "black", "block": "yellow"}
ORDER_WORDS = {2: ("left", "right"), 3: ("left", "middle", "right")}
# Phrasings per (relation, its word argument or None), true and negated: {x} the subject,
# {y} the other object.
PHRASINGS: dict[tuple[str, str | None], tuple[tuple[str, ...], tuple[str, ...]]] = {
    ("on", None): (
        ("{x} is on {y}", "{x} sits on {y}", "{x} rests on {y}", "{x} is on top of {y}"),
        ("{x} is not on {y}", "{x} does not sit on {y}", "{x} is not on top of {y}"),
    ),
    ("on_end", "left"): (
        ("{x} is on the left end of the block", "{x} sits at the left end of the block"),
        ("{x} is not on the left end of the block",),
    ),
    ("on_end", "right"): (
        ("{x} is on the right end of the block", "{x} sits at the right end of the block"),
        ("{x} is not on the right end of the block",),
    ),
    ("gone", None): (
        (
            "{x} is gone",
            "{x} is off the table",
            "{x} has fallen off the table",
            "{x} is no longer on the table",
        ),
        ("{x} is not gone", "{x} is still there", "{x} has not fallen off the table"),
    ),
    ("tipped", None): (
        ("{x} has tipped over", "{x} lies on its side", "{x} is knocked over"),
        ("{x} has not tipped over", "{x} is not knocked over"),
    ),
    ("upright", None): (
        ("{x} stands upright", "{x} is upright", "{x} is standing up"),
        ("{x} is not upright", "{x} is not standing up"),
    ),
    ("held", None): (
        ("the gripper holds {x}", "{x} is in the gripper", "the robot is holding {x}"),
        ("the gripper does not hold {x}", "{x} is not in the gripper"),
    ),
    ("lies", "across"): (
        ("{x} lies across", "{x} lies left to right", "{x} is turned across"),
        ("{x} does not lie across", "{x} is not turned across"),
    ),
    ("lies", "lengthwise"): (
        ("{x} lies lengthwise", "{x} points away from the camera", "{x} is turned lengthwise"),
        ("{x} does not lie lengthwise", "{x} is not turned lengthwise"),
    ),
    ("left_of", None): (("{x} is left of {y}", "{x} is to the left of {y}"), ("{x} is not left of {y}",)),
    ("right_of", None): (("{x} is right of {y}", "{x} is to the right of {y}"), ("{x} is not right of {y}",)),
    ("in_front_of", None): (
        ("{x} is in front of {y}", "{x} is nearer the camera than {y}"),
        ("{x} is not in front of {y}",),
    ),
    ("behind", None): (
        ("{x} is behind {y}", "{x} is farther from the camera than {y}"),
        ("{x} is not behind {y}",),
    ),
}
CLAUSES = (1, 2, 3)  # clauses per sampled statement, drawn with CLAUSE_P
CLAUSE_P = (0.6, 0.3, 0.1)
NEGATED_P = 0.3  # share of sampled clauses written negated
TRIES = 40  # draws before a sampler gives up on a clause of the truth asked


class SentenceError(UserError):
    """A sentence that cannot be read; the message names the word or clause."""


@dataclass(frozen=True)
class Clause:
    fact: Fact
    negated: bool = False

    def holds(self, state: State) -> bool:
        return self.fact.holds(state) != self.negated


@dataclass(frozen=True)
class Statement:
    """Clauses joined by "and"; `text` as written."""

    clauses: tuple[Clause, ...]
    text: str

    def holds(self, state: State) -> bool:
        return all(c.holds(state) for c in self.clauses)


# ---------------------------------------------------------------------------- names
def names(state: State) -> dict[int, tuple[str, ...]]:
    """The noun phrases that pick out each object of the state's scene, by slot: an object
    that shares its kind is named only by its place from the left, and only while every one
    of its kind stands on the table, clear of the others' by WORDS.beside."""
    out: dict[int, tuple[str, ...]] = {}
    kinds: dict[str, list[int]] = {}
    for k in sorted(state.members):
        kinds.setdefault(state.kind(k), []).append(k)
    for kind, slots in kinds.items():
        if len(slots) == 1:
            out[slots[0]] = (f"the {kind}", f"the {COLOURS[kind]} {kind}")
            continue
        if len(slots) not in ORDER_WORDS or not all(state.standing(k) for k in slots):
            continue
        order = sorted(slots, key=lambda k: state.poses[k, 0])
        xs = [state.poses[k, 0] for k in order]
        if min(np.diff(xs)) <= WORDS.beside:
            continue
        for k, word in zip(order, ORDER_WORDS[len(slots)], strict=True):
            out[k] = (f"the {word} {kind}", f"the {word} {COLOURS[kind]} {kind}")
    return out


# ---------------------------------------------------------------------------- writing
def write(clause: Clause, called: dict[int, tuple[str, ...]], rng: np.random.Generator) -> str:
    f = clause.fact
    word = f.other if isinstance(f.other, str) and f.other != "table" else None
    phrasings = PHRASINGS[(f.relation, word)][int(clause.negated)]
    y = "the table" if f.other == "table" else _pick(called.get(f.other, ("",)), rng)
    return _pick(phrasings, rng).format(x=_pick(called[f.subject], rng), y=y)


def _pick(options, rng: np.random.Generator):
    return options[int(rng.integers(len(options)))]


def _draw_fact(state: State, called: dict[int, tuple[str, ...]], rng: np.random.Generator) -> Fact | None:
    relation = _pick(RELATION_NAMES, rng)
    r = RELATIONS[relation]
    subjects = [k for k in called if state.kind(k) in r.subjects]
    if not subjects:
        return None
    subject = _pick(subjects, rng)
    others: list[int | str] = [k for k in called if state.kind(k) in r.other_kinds and k != subject]
    others += list(r.other_words)
    if not (r.other_kinds or r.other_words):
        return Fact(relation, subject)
    return Fact(relation, subject, _pick(others, rng)) if others else None


def sample_clause(state: State, truth: bool, rng: np.random.Generator, called=None) -> Clause | None:
    """A clause about `state` that is `truth`, clear of its words' vague edge
    (`Fact.clear`), or None when TRIES draws found none."""
    called = names(state) if called is None else called
    for _ in range(TRIES):
        fact = _draw_fact(state, called, rng)
        if fact is None:
            continue
        clause = Clause(fact, bool(rng.random() < NEGATED_P))
        if clause.holds(state) == truth and fact.clear(state):
            return clause
    return None


def sample_statement(state: State, truth: bool, rng: np.random.Generator) -> Statement | None:
    """A statement that is `truth` of `state`: every clause true, or all but one (the false
    one at a random place: a near miss is what teaches the model to read every clause)."""
    called = names(state)
    n = int(rng.choice(CLAUSES, p=CLAUSE_P))
    wanted = [True] * n
    if not truth:
        wanted[int(rng.integers(n))] = False
    clauses: list[Clause] = []
    for want in wanted:
        c = sample_clause(state, want, rng, called)
        if c is None or any(c.fact == d.fact for d in clauses):
            return None
        clauses.append(c)
    text = " and ".join(write(c, called, rng) for c in clauses)
    return Statement(tuple(clauses), text)


# ---------------------------------------------------------------------------- reading
def tokens(text: str) -> list[str]:
    return re.sub(r"[.,!]", " ", text.lower()).split()


@functools.cache
def vocabulary() -> tuple[str, ...]:
    """Every word a sentence may use, in a fixed order (the model's token ids)."""
    words = {"the", "and", "table", *COLOURS, *COLOURS.values()}
    words |= {w for order in ORDER_WORDS.values() for w in order}
    for true, negated in PHRASINGS.values():
        for p in true + negated:
            words |= set(tokens(p.replace("{x}", "").replace("{y}", "")))
    return tuple(sorted(words))


_NOUN = r"the(?: \w+)?(?: \w+)? (?:cup|ball|support|block)"


def _pattern(phrasing: str) -> re.Pattern:
    body = (
        re.escape(phrasing)
        .replace(r"\{x\}", f"(?P<x>{_NOUN})")
        .replace(r"\{y\}", f"(?P<y>{_NOUN}|the table)")
    )
    return re.compile(f"^{body}$")


_PATTERNS = [
    (relation, word, negated, _pattern(p))
    for (relation, word), options in PHRASINGS.items()
    for negated, phrasings in enumerate(options)
    for p in phrasings
]


@dataclass(frozen=True)
class Parts:
    """A clause as read, before its names are resolved: the relation, the subject's noun
    phrase, the other argument (a noun phrase, "the table", a word such as "left", or "" for
    none) and whether it is negated. What the agreement model reads."""

    relation: str
    subject: str
    other: str
    negated: bool


def clause_texts(text: str) -> list[str]:
    """The clauses of a sentence, each normalised; every word known, or a SentenceError."""
    known = set(vocabulary())
    words = tokens(text)
    if not words:
        raise SentenceError("the goal sentence is empty")
    unknown = [w for w in words if w not in known]
    if unknown:
        raise SentenceError(f"unknown word {unknown[0]!r}; the words known are: {', '.join(sorted(known))}")
    return " ".join(words).split(" and ")


def read_clause(part: str) -> Parts:
    """One normalised clause, read by the phrasing it is written in."""
    for relation, word, negated, pattern in _PATTERNS:
        m = pattern.match(part)
        if m is None:
            continue
        other = m.group("y") if "y" in pattern.groupindex else (word or "")
        return Parts(relation, m.group("x"), other, bool(negated))
    raise SentenceError(
        f"cannot read {part!r} as a clause; clauses read like 'the cup is on the block', "
        "'the ball is gone', 'the block lies across', joined by 'and'"
    )


def parse(text: str, state: State) -> Statement:
    """Read `text` into clauses, its names resolved in `state` (a task's start scene)."""
    called = {phrase: k for k, phrases in names(state).items() for phrase in phrases}
    clauses = []
    for part in clause_texts(text):
        p = read_clause(part)
        other: int | str | None = p.other or None
        if p.other == "the table":
            other = "table"
        elif p.other.startswith("the "):
            other = _resolve(p.other, called)
        clauses.append(Clause(Fact(p.relation, _resolve(p.subject, called), other), p.negated))
    return Statement(tuple(clauses), text)


def _resolve(phrase: str, called: dict[str, int]) -> int:
    if phrase not in called:
        raise SentenceError(
            f"{phrase!r} names no object of the scene; it has: {', '.join(sorted(called)) or 'none'}"
        )
    return called[phrase]
