"""Sentences about states: written from facts, sampled true or false, and read back.

A statement is one or more clauses joined by "and", each a fact (`words/facts.py`) or its
negation, written in one of several phrasings so that a model learns the relation and not a
template. Objects are named by kind ("the cup"), by colour ("the blue cup"), and, where the
scene holds several of a kind, by their order from the camera's left ("the left support").

`parse` reads a goal sentence into clauses against a state (a task's start scene). A sentence
in the phrasings above is read by them, as the agreement model was taught them; any other (an
instruction, several predicates or subjects, order words, relative references) is read by the
goal grammar (`grammar.py`, resolved in the scene by `reference.py`) and its clauses written
in the taught phrasings for the model. What cannot be read is a `SentenceError`: one line
naming the word or phrase that failed and the nearest reading that can (`suggest.py`).
"""

from __future__ import annotations

import functools
import re
from dataclasses import dataclass

import numpy as np

from afford.words.clauses import Clause, SentenceError, Statement
from afford.words.earley import spoken
from afford.words.facts import RELATION_NAMES, RELATIONS, Fact, State
from afford.words.grammar import Unread, words
from afford.words.reference import COLOURS, ORDER_WORDS, Ambiguous, Unresolved, names, understand
from afford.words.suggest import likeness, nearest, plain_sentences

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


def _match(part: str) -> Parts | None:
    try:
        return read_clause(part)
    except SentenceError:
        return None


# The names the sampler writes (`names`): a name of this form that fits no object of a state
# is refused by the taught reader itself; any other noun phrase is the grammar's to resolve.
_TAUGHT_NAME = re.compile(
    r"^the(?: (?:left|middle|right))?(?: (?:blue|red|black|yellow))? (?:cup|ball|support|block)$"
)


class _NoName(Exception):
    """A noun phrase that is none of the state's taught names."""


def _named(phrase: str, called: dict[str, int]) -> int:
    if phrase not in called:
        raise _NoName(phrase)
    return called[phrase]


def _taught_clauses(parts: list[Parts], state: State) -> tuple[Clause, ...] | None:
    """The clauses of parts read by the taught phrasings, their names resolved by the taught
    names; None where a relation is said of a kind it does not speak of."""
    called = {phrase: k for k, phrases in names(state).items() for phrase in phrases}
    clauses = []
    for p in parts:
        subject = _named(p.subject, called)
        other: int | str | None = p.other or None
        if p.other == "the table":
            other = "table"
        elif p.other.startswith("the "):
            other = _named(p.other, called)
        relation = RELATIONS[p.relation]
        if state.kind(subject) not in relation.subjects:
            return None
        if isinstance(other, int) and state.kind(other) not in relation.other_kinds:
            return None
        clauses.append(Clause(Fact(p.relation, subject, other), p.negated))
    return tuple(clauses)


def _taught(text: str, state: State) -> Statement | None:
    """`text` read as the agreement model was taught to read it (the phrasings and names the
    sampler writes), kept as its text; None where it is not written so. A taught name that
    fits no object is refused here, without the grammar: the sampler's sentences are read
    again on other states of their sequence while a dataset is drawn (`data.py`), often."""
    said = tokens(text)
    if not said or not set(said) <= set(vocabulary()):
        return None
    parts = [_match(part) for part in " ".join(said).split(" and ")]
    if any(p is None for p in parts):
        return None
    try:
        clauses = _taught_clauses(parts, state)
    except _NoName as e:
        if not _TAUGHT_NAME.match(str(e)):
            return None
        raise SentenceError(_no_name(str(e), said, state)) from None
    return None if clauses is None else Statement(clauses, text)


def _no_name(phrase: str, said: list[str], state: State) -> str:
    """The refusal of a taught name that fits no object, with the sentence under the name of
    each object of its kind (then any other) that reads."""
    kind = phrase.split()[-1]
    alike = [k for k in sorted(state.members) if state.kind(k) == kind]
    called = names(state)
    told = [called[k][0] for k in alike if k in called]
    which = f" ({', '.join(told)})" if told else " (too close together to tell apart by their order)"
    colour = next((w for w in phrase.split() if w in COLOURS.values()), None)
    if not alike:
        reason = f"{phrase!r} names no object of the scene: it has no {kind}s"
    elif colour is not None and colour != COLOURS[kind]:
        reason = f"{phrase!r} names no object of the scene: the {kind}s are {COLOURS[kind]}"
    elif phrase.split()[1] in ORDER_WORDS[3]:
        reason = f"{phrase!r} names no object of the scene: it has {len(alike)} {kind}s{which}"
    else:
        reason = f"{phrase!r} names no object alone: {len(alike)} {kind}s fit it{which}"
    text = " ".join(said)
    ranked = sorted(called, key=lambda k: (state.kind(k) != kind, k))
    for k in ranked:
        attempt = text.replace(phrase, called[k][0], 1)
        try:
            if _taught(attempt, state) is not None:
                return f"{reason}; did you mean {spoken(attempt.split())!r}?"
        except SentenceError:
            continue
    # Not the grammar's search: this refusal is met often while a dataset is drawn, and must
    # stay cheap; a plain sentence in the taught phrasings reads without the grammar.
    plain = sorted(plain_sentences(state), key=lambda p: -likeness(p, text))
    fallback = next((p for p in plain if _taught(p, state) is not None), "the cup is on the table")
    return f"{reason}; did you mean {fallback!r}?"


def written(clauses: tuple[Clause, ...], state: State) -> str | None:
    """The clauses as the agreement model reads them: each in its first taught phrasing, its
    objects by their first taught name; None where an object has no taught name (one of
    several of its kind that do not all stand clearly apart)."""
    called = names(state)
    parts = []
    for c in clauses:
        f = c.fact
        if f.subject not in called or (isinstance(f.other, int) and f.other not in called):
            return None
        word = f.other if isinstance(f.other, str) and f.other != "table" else None
        y = "the table" if f.other == "table" else called[f.other][0] if isinstance(f.other, int) else ""
        parts.append(PHRASINGS[(f.relation, word)][int(c.negated)][0].format(x=called[f.subject][0], y=y))
    return " and ".join(parts)


def _reads(text: str, state: State) -> bool:
    """Does `text` read in `state`, into clauses the agreement model can be given?"""
    try:
        return _taught(text, state) is not None or written(understand(text, state), state) is not None
    except (SentenceError, Unread, Unresolved, Ambiguous):
        return False


def _nearest(
    said: list[str], state: State, at: int | None = None, phrase: str = "", fits: tuple[str, ...] = ()
) -> str:
    return nearest(said, state, lambda t: _reads(t, state), at, phrase, fits)


# Words that pick out an object by what it is near but state no relation a goal can ask for.
_NEAR = ("next", "beside", "near", "by", "nearest", "closest")


def parse(text: str, state: State) -> Statement:
    """Read `text` into clauses, its names resolved in `state` (a task's start scene): by the
    taught phrasings where it is written in them, else by the goal grammar, its clauses then
    written in the taught phrasings as the statement's text (what the agreement model reads).
    A SentenceError names what failed and suggests the nearest reading that can."""
    taught = _taught(text, state)
    if taught is not None:
        return taught
    try:
        clauses = understand(text, state)
    except Unread as e:
        said = e.words
        if e.at is not None and e.reason.startswith("unknown word"):
            message = f"{e.reason} in {spoken(said)!r}"
        else:
            after = f", after {spoken(said[: e.at])!r}" if e.at else ""
            message = f"cannot read {spoken(said)!r} as a goal: {e.reason}{after}" if said else e.reason
            near = next((w for w in said if w in _NEAR), None)
            if near is not None:
                message += (
                    f" ({near!r} only picks out an object, as in 'the cup next to the ball'; a goal asks for "
                    "on, left of, right of, in front of or behind)"
                )
        raise SentenceError(f"{message}; did you mean {_nearest(said, state, at=e.at)!r}?") from None
    except Unresolved as e:
        suggestion = _nearest(words(text), state, phrase=e.phrase, fits=e.fits)
        raise SentenceError(f"{e.reason}; did you mean {suggestion!r}?") from None
    except Ambiguous as e:
        readings = [written(c, state) or _listing(c, state) for c in e.readings]
        raise SentenceError(
            f"{text!r} reads {len(readings)} ways in this scene: "
            + " or ".join(map(repr, readings[:3]))
            + f"; did you mean {readings[0]!r}?"
        ) from None
    model_text = written(clauses, state)
    if model_text is None:
        called = names(state)
        said = {k for c in clauses for k in (c.fact.subject, c.fact.other) if isinstance(k, int)}
        unnamed = sorted(k for k in said if k not in called)
        raise SentenceError(
            f"{text!r} names {', '.join(state.slots[k] for k in unnamed)}, which the agreement model has no "
            f"name for: it tells objects of a kind apart only by their order from the left, while all "
            f"stand clearly apart; did you mean {_nearest(words(text), state)!r}?"
        )
    return Statement(clauses, model_text)


def _listing(clauses: tuple[Clause, ...], state: State) -> str:
    return " and ".join(
        f"{'not ' if c.negated else ''}{c.fact.relation} {state.slots[c.fact.subject]}"
        + (
            f" {c.fact.other if isinstance(c.fact.other, str) else state.slots[c.fact.other]}"
            if c.fact.other is not None
            else ""
        )
        for c in clauses
    )
