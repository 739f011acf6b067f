"""Goals and names whose meaning depends on where things stand at the start: a turn,
"between", a swap, "where the ball was", the noun phrases "the other support", "the empty
support", "the support the ball is on", and order words ("the left cup", "the outer cups");
`Unresolved` where the scene gives one no meaning.

The grammar reads these as pseudo-relations (`Pred("turn", 90)`, `Pred("between", nouns)`,
`Pred("swap")`) or as marks on a noun phrase (`Noun.other`, `.bare`, `.bears`, quantity
"host"); here each becomes the facts it means in the task's start scene, so that the goal
is still a set of clauses over `facts.RELATIONS`, the ones the agreement model scores and the
success predicate checks:

- a turn is said of the block's lie: a quarter turn (90 or 270 degrees, "a quarter turn", no
  angle at all) asks for the other lie than the one at the start, a half turn (180, 360,
  "around") for the same; any other angle is refused, as the block lies only across or
  lengthwise;
- "between A and B" is right of the left one and left of the right one (or in front of the
  back one and behind the front one, where they stand one behind the other);
- "swap A and B": each on what the other rests on at the start where those differ, else each
  on the other's side of it;
- "where B was / is": on what B rests on at the start, the table included.
"""

from __future__ import annotations

from afford.sim.constants import WORDS
from afford.words.clauses import Noun
from afford.words.facts import State, across, lengthwise, on, on_end
from afford.words.lexicon import ORDER

SIDES = ((0, "right_of", "left_of"), (1, "behind", "in_front_of"))  # axis, the subject of each end


class Unresolved(Exception):
    """A noun phrase or clause that fits nothing the scene allows: the reason, the words of
    the phrase that failed (a suggestion replaces them) and the kinds that would fit there."""

    def __init__(self, reason: str, phrase: str = "", fits: tuple[str, ...] = ()) -> None:
        super().__init__(reason)
        self.reason, self.phrase, self.fits = reason, phrase, fits


def own(noun: Noun) -> tuple[str, ...]:
    """The kind a failed phrase names, whose objects a suggestion names first."""
    return (noun.kind,) if noun.kind else ()


def host(state: State, k: int) -> int | str | None:
    """What slot k rests on at the start: another object, "table", or None (held, gone)."""
    for o in sorted(state.members):
        if o != k and state.standing(o) and on(state, k, o):
            return o
    return "table" if on(state, k, "table") else None


def bearing(state: State, k: int) -> list[int]:
    """The objects resting on slot k at the start."""
    return [o for o in sorted(state.members) if o != k and state.standing(o) and on(state, o, k)]


def belongs(state: State, k: int, owner: int) -> bool:
    """Is slot k the owner's at the start ("its post", "the ball's post", "the block's cup"):
    resting on it, or bearing it?"""
    return k != owner and (k in bearing(state, owner) or owner in bearing(state, k))


def owned(state: State, fits: list[int], owners: list[list[int]]) -> list[int]:
    """The objects of `fits` owned by the first group of `owners` that owns any."""
    for group in owners:
        mine = [k for k in fits if any(belongs(state, k, o) for o in group)]
        if mine:
            return mine
    return []


def sole_owner(state: State, fits: list[int]) -> list[int]:
    """The one object of the scene that owns any of `fits` ("its post" said where nothing
    named before it has one), or none where several do."""
    owners = [o for o in sorted(state.members) if any(belongs(state, k, o) for k in fits)]
    return owners if len(owners) == 1 else []


def turned(state: State, k: int, angle: int, name: str) -> str:
    """The lie (across or lengthwise) a turn of `angle` degrees gives the block k."""
    if angle % 90:
        raise Unresolved(
            f"a turn of {angle} degrees leaves {name!r} neither across nor lengthwise, the two ways "
            "a goal can ask it to lie",
            name,
        )
    if across(state, k):
        start = "across"
    elif lengthwise(state, k):
        start = "lengthwise"
    else:
        raise Unresolved(
            f"{name!r} lies neither across nor lengthwise at the start: say which way it should lie", name
        )
    quarter = (angle // 90) % 2 == 1
    return {"across": "lengthwise", "lengthwise": "across"}[start] if quarter else start


def between(state: State, ends: list[int], words: str) -> list[tuple[str, int]]:
    """The clauses (relation, other) that put an object between the two objects `ends`: on the
    axis along which they stand further apart."""
    if len(ends) != 2:
        raise Unresolved(f"'between {words}' needs two objects, not {len(ends)}", words)
    a, b = ends
    axis, toward_high, toward_low = max(SIDES, key=lambda s: abs(state.poses[a, s[0]] - state.poses[b, s[0]]))
    if abs(state.poses[a, axis] - state.poses[b, axis]) <= 2 * WORDS.beside:
        raise Unresolved(
            f"'between {words}': they stand too close together for anything to go between", words
        )
    low, high = sorted(ends, key=lambda k: state.poses[k, axis])
    return [(toward_high, low), (toward_low, high)]


def swapped(state: State, k: int, partner: int, names: tuple[str, str]) -> tuple[str, int | str]:
    """The clause (relation, other) that puts k where `partner` is at the start."""
    mine, theirs = host(state, k), host(state, partner)
    if mine != theirs and None not in (mine, theirs) and state.kind(k) in ("cup", "ball"):
        return "on", theirs
    for axis, toward_high, toward_low in SIDES:
        gap = state.poses[partner, axis] - state.poses[k, axis]
        if abs(gap) > WORDS.beside:
            return (toward_high if gap > 0 else toward_low), partner
    raise Unresolved(f"{names[0]!r} and {names[1]!r} stand too close together to swap", names[0])


def other_than(noun: Noun, fits: list[int], said: set[int], subject: int | None, state: State) -> list[int]:
    """For "the other support": those of `fits` not said before in the sentence, not the subject,
    and not what the subject rests on or bears at the start; refused where that leaves out
    none (the scene has no other)."""
    near = set() if subject is None else {subject, *bearing(state, subject)}
    if subject is not None and isinstance(host(state, subject), int):
        near.add(host(state, subject))
    kept = [k for k in fits if k not in said | near]
    if len(kept) == len(fits):
        raise Unresolved(
            f"{noun.words!r}: nothing said before it is one of them, so there is no other", noun.words
        )
    return kept


def where(noun: Noun, subject: int, state: State, resolved: list[int]) -> int | str:
    """The other argument of "where B was": what B rests on at the start."""
    if len(resolved) != 1:
        raise Unresolved(f"{noun.words!r}: where one object is, not {len(resolved)}", noun.words)
    (b,) = resolved
    place = host(state, b)
    if place is None:
        raise Unresolved(f"{noun.words!r}: it rests on nothing at the start", noun.words)
    if place == subject:
        raise Unresolved(f"{noun.words!r} is on the object to be put there", noun.words)
    return place


def other_end(state: State, k: int, name: str) -> str:
    """For "the other end of the block": the end k does not rest on at the start."""
    for side, other in (("left", "right"), ("right", "left")):
        if on_end(state, k, side):
            return other
    raise Unresolved(
        f"{name!r} rests on neither end of the block at the start, so 'the other end' is neither", name
    )


def bearing_of(state: State, k: int) -> list[int]:
    """What slot k rests on at the start, as a list (empty: the table, or nothing)."""
    place = host(state, k)
    return [place] if isinstance(place, int) else []


def in_order(noun: Noun, word: str, fits: list[int], state: State) -> list[int]:
    """The one of `fits` an order word picks: by place from the camera's left (x) or from its
    front (y), among those standing on the table, clear of its neighbours by WORDS.beside (as
    the taught names are)."""
    axis, rank = ORDER[word]
    standing = [k for k in fits if state.standing(k)]
    if rank == "ends":  # "the outer cups": the first and the last of three or more
        if len(standing) < 3:
            raise Unresolved(
                f"{noun.words!r}: of {len(standing)} none is between the others", noun.words, own(noun)
            )
        ends = sorted(standing, key=lambda k: state.poses[k, 0])
        return [ends[0], ends[-1]]
    if len(standing) <= 1 and rank in (0, -1):
        return standing or fits  # "the left cup" of one cup: it
    column = 0 if axis == "x" else 1
    order = sorted(standing, key=lambda k: state.poses[k, column])
    if axis == "x" and noun.from_right and word in ("first", "second", "third"):
        order = order[::-1]
    if rank is None:
        if len(order) % 2 == 0:
            raise Unresolved(f"{noun.words!r}: of {len(order)} none is in the middle", noun.words, own(noun))
        rank = len(order) // 2
    if not -len(order) <= rank < len(order):
        raise Unresolved(
            f"{noun.words!r} names no object of the scene: there are {len(order)}", noun.words, own(noun)
        )
    i = rank % len(order)
    here = state.poses[order[i], column]
    gaps = [abs(here - state.poses[order[j], column]) for j in (i - 1, i + 1) if 0 <= j < len(order)]
    if gaps and min(gaps) <= WORDS.beside:
        side = "side by side" if axis == "x" else "one behind the other"
        raise Unresolved(
            f"{noun.words!r}: they stand too close {side} to tell which is meant; name it another way",
            noun.words,
            own(noun),
        )
    return [order[i]]
