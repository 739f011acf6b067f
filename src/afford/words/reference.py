"""What the words of a goal refer to in a scene, and the clauses they say of it.

A parse (`grammar.read`) names objects by kind, colour, order ("the second cup", "the cup on
the left"), relation to another ("the cup left of the ball", "the cup that is upright") or
pronoun ("put it on the block"); here each noun phrase is resolved against the task's start
state to the object slots it names, and each relation said of it becomes a `Clause`. A phrase
that names no object, or more than one where one is meant, is refused with its words; so is a
sentence whose parses read to different clauses in the scene and that the scene cannot tell
apart.
"""

from __future__ import annotations

from contextlib import suppress
from dataclasses import dataclass, field, replace

import numpy as np

from afford.sim.constants import WORDS
from afford.words import derived, grammar
from afford.words.clauses import Clause
from afford.words.derived import Unresolved, own
from afford.words.facts import RELATIONS, Fact, State
from afford.words.parses import Item, Noun, Pred

COLOURS = {"cup": "blue", "ball": "red", "support": "black", "block": "yellow"}
ORDER_WORDS = {2: ("left", "right"), 3: ("left", "middle", "right")}
PLURALS = {"cup": "cups", "ball": "balls", "support": "supports", "block": "blocks", None: "objects"}
# What a relation says of its subject, for messages: "'the ball' cannot be upright".
SAID = {
    "on": "on something", "on_end": "on an end of the block", "gone": "gone", "tipped": "tipped over",
    "upright": "upright", "held": "held", "lies": "turned across or lengthwise",
    "left_of": "left of something", "right_of": "right of something",
    "in_front_of": "in front of something", "behind": "behind something",
}  # fmt: skip
QUANTITIES = {"both": 2, "two": 2, "three": 3}
KINDS = ("cup", "ball", "support", "block")
# The relation whose kinds a pseudo-relation (`derived.py`) is said of.
STANDS_FOR = {"turn": "lies", "between": "left_of", "swap": "left_of"}
SAID |= {"turn": "turned", "between": "between two objects", "swap": "swapped"}
PLACES = ("on", "on_end", "left_of", "right_of", "in_front_of", "behind", "lies")  # what a gone object is not


class Ambiguous(Exception):
    """A sentence whose parses read to different clauses in the scene."""

    def __init__(self, readings: list[tuple[Clause, ...]]) -> None:
        super().__init__("reads more than one way")
        self.readings = readings


# ---------------------------------------------------------------------------- names
def names(state: State) -> dict[int, tuple[str, ...]]:
    """The noun phrases that pick out each object of the state's scene, by slot: an object
    that shares its kind is named only by its place from the left, and only while every one
    of its kind stands on the table, clear of the others' by WORDS.beside. These are the names
    the agreement model was taught; a goal may name objects in more ways (`resolve`)."""
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


def _listed(state: State, slots: list[int]) -> str:
    called = names(state)
    return ", ".join(called[k][0] if k in called else state.slots[k] for k in slots)


# ---------------------------------------------------------------------------- noun phrases
@dataclass
class _Context:
    """What a sentence has named so far, most recent first, for "it" and "them"; and how loose
    it is (relative references that picked nothing out, as the object was the only one of its
    kind already; verbs read as asking nothing), which makes a parse less likely meant."""

    mentioned: list[list[int]]
    subjects: list[int]
    loose: int = 0
    # "the right one": the kind of the last noun said in the same role (subject or other); "the
    # other one" said where its role has none: the subject's ("... right of the other one")
    kinds: dict[str, str] = field(default_factory=dict)
    role: str = "subject"
    subject: int | None = None  # the subject of the clause being read, for "the other support"
    inner: list[int] = field(default_factory=list)  # named inside the item's names, for "it"
    source: int | None = None  # the subject whose start a "from" phrase names


def resolve(noun: Noun, state: State, context: _Context) -> list[int]:
    """The slots `noun` names in `state` (its start scene); Unresolved when it names none, or
    several where it names one. Pronouns are resolved by the clause (`_pronoun`)."""
    if noun.quantity == "it":  # only a clause's own subject or object may be "it" (`_pronoun`)
        raise Unresolved(f"{noun.words!r} cannot name an object inside another name", noun.words)
    if noun.quantity == "them":
        if not context.subjects:
            raise Unresolved(f"{noun.words!r} refers to nothing said before it", noun.words)
        return list(context.subjects)
    if noun.quantity == "everything":
        return sorted(state.members)
    if noun.quantity == "host":
        raise Unresolved(f"{noun.words!r} names a place, not an object", noun.words)
    kind = noun.kind
    if kind is None and noun.colour is None and (noun.other or noun.words.split()[-1] in ("one", "ones")):
        kind = context.kinds.get(context.role, context.kinds.get("subject") if noun.other else None)
    role = context.role
    fits = [k for k in sorted(state.members) if kind is None or state.kind(k) == kind]
    plural = PLURALS[kind]
    if not fits:
        raise Unresolved(f"{noun.words!r} names no object of the scene: it has no {plural}", noun.words)
    if noun.colour is not None:
        fits = [k for k in fits if COLOURS[state.kind(k)] == noun.colour]
        if not fits:
            told = f"the {plural} are {COLOURS[kind]}" if kind else f"nothing is {noun.colour}"
            raise Unresolved(f"{noun.words!r} names no object of the scene: {told}", noun.words, own(noun))
    for pred in noun.restrict:
        before = len(fits)
        fits = [k for k in fits if _holds_of(pred, k, state, context)]
        context.loose += before == 1
    for far, others in ((False, noun.nearest), (True, noun.farthest)):
        for other in others:
            before = len(fits)
            fits = _nearest(noun, fits, other, state, context, far)
            context.loose += before == 1
    if kind is not None:  # "every cup except the middle one": the one is a cup
        context.kinds[role] = kind
    fits = _described(noun, fits, state, context)
    if not fits:
        raise Unresolved(f"{noun.words!r} names no object of the scene", noun.words, own(noun))
    for word in noun.order:
        fits = derived.in_order(noun, word, fits, state)
    if kind is not None:  # after the phrases inside it ("the cup left of the ball": cup)
        context.kinds[role] = kind
    return _counted(noun, fits, state)


def _described(noun: Noun, fits: list[int], state: State, context: _Context) -> list[int]:
    """`fits` narrowed by what the phrase says of them on the start scene: nothing on it ("the
    empty support"), something on it ("the support the ball is on"), not the ones left out
    ("except the middle one"), not the ones said before ("the other support")."""
    if context.source is not None and len(fits) > 1:  # "from the support": the one it is on
        fits = [k for k in fits if k in derived.bearing_of(state, context.source)] or fits
    if noun.owner:
        fits = derived.owned(state, fits, _owners(noun.owner[0], fits, state, context))
    if noun.bare:
        fits = [k for k in fits if not derived.bearing(state, k)]
    for other in noun.bears:
        borne = resolve(other, state, context)
        context.inner += borne
        fits = [k for k in fits if all(b in derived.bearing(state, k) for b in borne)]
    for other in noun.excluded:
        left_out = set(resolve(other, state, context))
        fits = [k for k in fits if k not in left_out]
    if noun.other:
        said = {k for group in context.mentioned for k in group}
        fits = derived.other_than(noun, fits, said, context.subject, state)
    return fits


def _owners(owner: Noun, fits: list[int], state: State, context: _Context) -> list[list[int]]:
    """Whose "its" may be, most likely first: the clause's subject, what was named before (most
    recent first), the one object that owns one of `fits`. "Their": what was said last."""
    if owner.quantity == "them":
        return [context.subjects]
    if owner.quantity == "it":
        said = [[context.subject]] if context.role == "other" and context.subject is not None else []
        return [*said, *context.mentioned, derived.sole_owner(state, fits)]
    context.inner += (named := resolve(owner, state, context))
    return [named]


def _counted(noun: Noun, fits: list[int], state: State) -> list[int]:
    want = QUANTITIES.get(noun.quantity)
    if noun.quantity in ("one", "some") and len(fits) > 1:
        listed = f"{len(fits)} {PLURALS[noun.kind]} fit it ({_listed(state, fits)})"
        raise Unresolved(f"{noun.words!r} names no object alone: {listed}", noun.words, own(noun))
    if want is not None and len(fits) != want:
        counted = f"{len(fits)} {PLURALS[noun.kind] if len(fits) != 1 else noun.kind or 'object'}"
        raise Unresolved(f"{noun.words!r}: the scene has {counted}, not {want}", noun.words, own(noun))
    return fits


def _holds_of(pred: Pred, k: int, state: State, context: _Context) -> bool:
    """Does relation `pred` hold of slot k in the start state (a relative reference)?"""
    relation = RELATIONS[pred.relation]
    if state.kind(k) not in relation.subjects:
        return False
    if isinstance(pred.other, tuple):
        others = [o for n in pred.other for o in resolve(n, state, context)]
        context.inner += others
        facts = [Fact(pred.relation, k, o) for o in others if o != k]
        if len(facts) < len(others):
            return False
    else:
        facts = [Fact(pred.relation, k, pred.other)]
    return all(f.holds(state) != pred.negated for f in facts)


def _nearest(
    noun: Noun, fits: list[int], other: Noun, state: State, context: _Context, far: bool = False
) -> list[int]:
    """The one of `fits` nearest `other` on the table (`far`: farthest), clearly apart from the next."""
    said = noun.words, own(noun)
    if other.quantity == "it":
        raise Unresolved(f"{noun.words!r}: say by name what it is {'far from' if far else 'near'}", *said)
    (o, *more) = _counted(other, resolve(other, state, context), state)
    context.inner.append(o)
    if more:
        raise Unresolved(f"{noun.words!r}: near one object, not {len(more) + 1}", *said)
    ranked = sorted(
        (float(np.linalg.norm(state.poses[k, :2] - state.poses[o, :2])), k)
        for k in fits
        if k != o and state.standing(k) and state.standing(o)
    )
    ranked = ranked[::-1] if far else ranked
    if len(ranked) > 1 and abs(ranked[1][0] - ranked[0][0]) <= WORDS.beside:
        raise Unresolved(
            f"{noun.words!r}: two objects are about as {'far' if far else 'near'}; name it otherwise", *said
        )
    return [ranked[0][1]] if ranked else []


def _pronoun(noun: Noun, kinds: tuple[str, ...], state: State, context: _Context) -> int:
    """What "it" refers to: the object most recently named that the relation can be said of
    (a subject before the objects of the same item), so that "put the ball on the block and
    knock it over" knocks over the block, which a ball cannot be."""
    for group in context.mentioned:
        for k in group:
            if state.kind(k) in kinds:
                return k
    raise Unresolved(f"{noun.words!r} refers to nothing said before it that it could be", noun.words)


# ---------------------------------------------------------------------------- clauses
def _slots(
    nouns, kinds: tuple[str, ...], state: State, context: _Context, role: str = "subject", known=None
) -> list[tuple[int, Noun]]:
    """The slots each of `nouns` names, a pronoun as one of `kinds` can be; `known`: the slots
    of the others where already resolved (a subject said once, of several relations)."""
    context.role = role
    known = {} if known is None else known
    out = []
    for i, n in enumerate(nouns):
        if n.quantity == "it":
            out.append((_pronoun(n, kinds, state, context), n))
            continue
        if i not in known:
            known[i] = resolve(n, state, context)
        out += [(k, n) for k in known[i]]
    slots = [k for k, _ in out]
    if len(set(slots)) < len(slots):  # "on the block and the right one": a parse that misread
        raise Unresolved(f"{' and '.join(n.words for n in nouns)!r} names one object twice")
    return out


def _quietly(noun: Noun) -> bool:
    """A phrase that names a group by its kind ("every object"), whose members a relation may
    not fit: those are left out rather than refused."""
    return noun.kind is None and noun.quantity in ("every", "everything", "none", "them")


def clauses_of(items: tuple[Item, ...], state: State) -> tuple[tuple[Clause, ...], int]:
    """The clauses a parse says of `state`, in the order said, and how many of its relative
    references were loose (picked nothing out)."""
    context = _Context([], [])
    said: list[tuple[Clause, bool]] = []  # each clause, and whether it is passing (held on the way)
    last_preds: tuple[Pred, ...] = ()
    for at, item in enumerate(items):
        preds = item.preds if item.preds is not None else last_preds
        if item.explained:  # "swap them: the ball on the block and ...": what the rest names
            context.subjects = _named(items[at + 1 :], state)
            context.mentioned.insert(0, context.subjects)
        subjects_said: list[int] = []
        others_said: list[int] = []
        known: dict[int, list[int]] = {}
        if not preds:  # "move the ball so that ...": named, for "it", nothing asked of it
            context.loose += 1
            subjects_said += [k for k, _ in _slots(item.subjects, KINDS, state, context)]
        for pred in preds:
            relation = RELATIONS[STANDS_FOR.get(pred.relation, pred.relation)]
            subjects = _slots(item.subjects, relation.subjects, state, context, known=known)
            for s, noun in subjects:
                subjects_said.append(s)
                if state.kind(s) not in relation.subjects:
                    if pred.implied or _quietly(noun):
                        continue
                    raise Unresolved(
                        f"{noun.words!r} cannot be {SAID[pred.relation]}: "
                        f"that is said of {_kinds(relation.subjects)}",
                        noun.words,
                        relation.subjects,
                    )
                context.subject = s
                context.mentioned.insert(0, context.inner)
                context.source = s if pred.source else None
                try:
                    pairs = _pairs(pred, s, noun, subjects, state, context)
                finally:
                    del context.mentioned[0]
                    context.source = None
                for name, other in pairs:
                    if isinstance(other, int):
                        others_said.append(other)
                    denied = noun.denied != pred.negated
                    said.append((Clause(Fact(name, s, other), denied), pred.passing))
        context.mentioned = [subjects_said, others_said, context.inner, *context.mentioned]
        context.inner = []
        context.subjects = list(dict.fromkeys(subjects_said)) or context.subjects
        last_preds = preds
    return _settled(said, state), context.loose


def _named(items: tuple[Item, ...], state: State) -> list[int]:
    """The subjects `items` name by name (not by a pronoun), for a pronoun said before them."""
    out: list[int] = []
    for n in (n for item in items for n in item.subjects if n.quantity not in ("it", "them")):
        with suppress(Unresolved):  # refused where the item is read
            out += resolve(n, state, _Context([], []))
    return list(dict.fromkeys(out))


def _pairs(
    pred: Pred, s: int, noun: Noun, subjects, state: State, context: _Context
) -> list[tuple[str, object]]:
    """The clauses (relation, other) that `pred` makes of subject s: one per other argument,
    or those a scene-dependent phrase means at the start (`derived.py`)."""
    if pred.relation == "turn":
        return [("lies", derived.turned(state, s, int(pred.other), noun.words))]
    if pred.relation == "between":
        ends = [k for n in pred.other for k in resolve(n, state, context)]
        return derived.between(state, ends, " and ".join(n.words for n in pred.other))
    if pred.relation == "swap":
        partners = [k for k, _ in subjects if k != s]
        if len(subjects) != 2 or len(partners) != 1:
            raise Unresolved(f"a swap is of two objects, not {len(subjects)}", noun.words)
        words = tuple(n.words for _, n in subjects)
        return [derived.swapped(state, s, partners[0], (words[0], words[1]))]
    if isinstance(pred.other, tuple) and len(pred.other) == 1 and pred.other[0].quantity == "host":
        place = pred.other[0]
        (b,) = place.bears
        borne = [s] if b.quantity == "it" else resolve(b, state, context)
        return [(pred.relation, derived.where(place, s, state, borne))]
    if pred.relation == "on_end" and pred.other == "other":
        _others(replace(pred, other="left"), s, state, context)  # the host is the block
        return [("on_end", derived.other_end(state, s, _listed(state, [s])))]
    return [(pred.relation, other) for other in _others(pred, s, state, context)]


def _others(pred: Pred, s: int, state: State, context: _Context) -> list[int | str | None]:
    """The other argument of each clause `pred` makes of subject s."""
    relation = RELATIONS[pred.relation]
    if pred.relation == "on_end":
        for k, noun in _slots(pred.host, ("block",), state, context, "other"):
            if state.kind(k) != "block":
                raise Unresolved(
                    f"{noun.words!r} has no ends a goal can speak of: the block has", noun.words, ("block",)
                )
            context.inner.append(k)  # named, for "its other end"
        return [pred.other]
    if not isinstance(pred.other, tuple):
        if pred.other is not None and pred.other not in relation.other_words:
            raise Unresolved(f"{_listed(state, [s])} cannot be {SAID[pred.relation]}")
        return [pred.other]
    out: list[int | str | None] = []
    for k, noun in _slots(pred.other, relation.other_kinds, state, context, "other"):
        if state.kind(k) not in relation.other_kinds:
            raise Unresolved(
                f"nothing can be {pred.relation.replace('_', ' ')} {noun.words!r}: only "
                f"{_kinds(relation.other_kinds)} can be named there",
                noun.words,
                relation.other_kinds,
            )
        if k == s:
            raise Unresolved(f"{noun.words!r} cannot be {pred.relation.replace('_', ' ')} itself", noun.words)
        out.append(k)
    return out


def _kinds(kinds: tuple[str, ...]) -> str:
    words = [PLURALS[k] if k != "block" else "the block" for k in kinds]
    return words[0] if len(words) == 1 else ", ".join(words[:-1]) + " and " + words[-1]


def _settled(said: list[tuple[Clause, bool]], state: State) -> tuple[Clause, ...]:
    """The goal's clauses: a passing "held" left out where a later clause puts the object
    somewhere or lets go of it ("pick up the ball and put it on the block" ends with the ball
    on the block), each clause once, and none said both ways."""
    kept: list[Clause] = []
    for i, (clause, passing) in enumerate(said):
        later = {c.fact.subject for c, _ in said[i + 1 :] if c.fact.relation != "held" or c.negated}
        if passing and clause.fact.subject in later:
            continue
        if clause not in kept:
            kept.append(clause)
    for c in kept:
        places = {
            d.fact.other for d in kept if d.fact == replace(c.fact, other=d.fact.other) and not d.negated
        }
        if c.fact.relation in ("on", "on_end") and not c.negated and len(places) > 1:
            # an object rests on one thing: a parse that reads two hosts misread the sentence
            raise Unresolved(f"{_listed(state, [c.fact.subject])} cannot be on two things at once")
        if c.fact.relation == "lies" and not c.negated and len(places) > 1:
            raise Unresolved(f"{_listed(state, [c.fact.subject])} cannot lie across and lengthwise at once")
        if c.fact.relation == "gone" and not c.negated:
            placed = [d for d in kept if d.fact.subject == c.fact.subject and d.fact.relation in PLACES]
            if any(not d.negated for d in placed):
                subject = _listed(state, [c.fact.subject])
                raise Unresolved(f"it says {subject} is gone and also where it should be")
        if Clause(c.fact, not c.negated) in kept:
            subject = _listed(state, [c.fact.subject])
            raise Unresolved(f"it says both that {subject} is {SAID[c.fact.relation]} and that it is not")
    # on an end of the block is on the block: saying both is one goal ("the ball on its left end")
    ends = {c.fact.subject for c in kept if c.fact.relation == "on_end" and not c.negated}
    blocks = {k for k in state.members if state.kind(k) == "block"}
    on_block = {c for c in kept if c.fact.relation == "on" and not c.negated and c.fact.subject in ends}
    return tuple(c for c in kept if c not in on_block or c.fact.other not in blocks)


def understand(text: str, state: State) -> tuple[Clause, ...]:
    """The clauses `text` says of `state`: every parse resolved in the scene; those that fail
    left out; of the rest, those with a relative reference that picks out nothing, or a verb
    read as asking nothing before a purpose ("turn the block so that"), are less likely meant.
    grammar.Unread, Unresolved (the first parse's failure when none resolves) or Ambiguous."""
    readings = grammar.read(text)
    found: list[tuple[tuple[Clause, ...], int]] = []
    failed: list[Unresolved] = []
    for items in readings:
        try:
            found.append(clauses_of(items, state))
        except Unresolved as e:
            failed.append(e)
    if not found:
        raise failed[0]
    tightest = min(loose for _, loose in found)
    distinct = list(dict.fromkeys(c for c, loose in found if loose == tightest))
    if len(distinct) > 1:
        raise Ambiguous(distinct)
    return distinct[0]
