"""What a parse of a goal says: noun phrases, relations and items, before the scene resolves them.

`grammar.py` parses a sentence; `Build` turns each parse tree into `Item`s, one method per rule
of the grammar, each giving that rule's meaning: a complement the relation it states, an
instruction the state it asks for ("knock the cup over": the cup tipped over), a noun phrase
what it says of the objects it names (kind, colour, order words, relative references).
"""

from __future__ import annotations

from dataclasses import dataclass, replace

from lark import Transformer, v_args

# Nouns by the kind they name; None: any kind ("the red one", "everything").
KINDS = {
    "cup": "cup",
    "mug": "cup",
    "ball": "ball",
    "sphere": "ball",
    "support": "support",
    "pillar": "support",
    "pedestal": "support",
    "block": "block",
    "brick": "block",
    "plank": "block",
    "beam": "block",
    "bar": "block",
    "one": None,
    "thing": None,
    "object": None,
}
# Order words, each an (axis, rank) among the objects a noun phrase fits, the axis from the
# camera: "x" counts from the left (a negative rank from the right), "y" from the front.
# "middle" is the middle one of an odd number.
ORDER = {
    "left": ("x", 0),
    "leftmost": ("x", 0),
    "first": ("x", 0),
    "second": ("x", 1),
    "third": ("x", 2),
    "right": ("x", -1),
    "rightmost": ("x", -1),
    "last": ("x", -1),
    "middle": ("x", None),
    "centre": ("x", None),
    "center": ("x", None),
    "central": ("x", None),
    "front": ("y", 0),
    "near": ("y", 0),
    "nearest": ("y", 0),
    "closest": ("y", 0),
    "back": ("y", -1),
    "rear": ("y", -1),
    "far": ("y", -1),
    "farthest": ("y", -1),
    "furthest": ("y", -1),
}
PLACES = {  # "the cup on the left": an order word said after the noun
    "left": "left",
    "right": "right",
    "middle": "middle",
    "centre": "middle",
    "center": "middle",
    "front": "front",
    "back": "back",
}
COLOUR_WORDS = ("blue", "red", "black", "yellow")


@dataclass(frozen=True)
class Noun:
    """A noun phrase as said, before it is resolved against a scene.

    words: as written, for messages; kind: a key of the scene's kinds, or None (a pronoun,
    "the red one"); quantity: "one" ("the cup"), "some" ("a cup"), "every" ("all cups", "the
    cups"), "both", "two"/"three" ("the two cups"), "none" ("no cup"), "it", "them",
    "everything"; denied: the clauses about it are negated ("neither the cup nor the ball",
    "no cup"); colour and order words; restrict: relations it must stand in on the start
    scene ("the cup left of the ball", "the cup that is upright")."""

    words: str
    kind: str | None
    quantity: str
    colour: str | None = None
    order: tuple[str, ...] = ()
    from_right: bool = False
    restrict: tuple[Pred, ...] = ()
    nearest: tuple[Noun, ...] = ()
    denied: bool = False


@dataclass(frozen=True)
class Pred:
    """One relation said of a subject: its name (a key of facts.RELATIONS), its other argument
    (the nouns of a list, a word such as "table" or "left", or None) and whether it is negated.
    host: the block an end belongs to ("the left end of the block"); implied: said by a verb
    ("stands on" implies upright) and dropped where the subject cannot take it; passing: held
    on the way ("pick up the cup and put it on the block"), dropped when a later clause of the
    sentence puts its subject somewhere."""

    relation: str
    other: tuple[Noun, ...] | str | None = None
    negated: bool = False
    host: tuple[Noun, ...] = ()
    implied: bool = False
    passing: bool = False


@dataclass(frozen=True)
class Item:
    """One thing the goal asks: its subjects and what is said of them (preds None: what was
    said in the item before, "and so is the cup"); instruction: said as an order ("put ...")."""

    subjects: tuple[Noun, ...]
    preds: tuple[Pred, ...] | None
    instruction: bool = False


# ---------------------------------------------------------------------------- meaning
def _nouns(x) -> tuple[Noun, ...]:
    return x if isinstance(x, tuple) else (x,)


def _negate(preds: tuple[Pred, ...]) -> tuple[Pred, ...]:
    return tuple(replace(p, negated=not p.negated) for p in preds)


def _first_negated(preds: tuple[Pred, ...]) -> tuple[Pred, ...]:
    """A negative verb ("does not sit", "should not be") denies the complement that follows it,
    as "not" does: "the cup should not be upright on the block" is "not upright, on the block"."""
    return (replace(preds[0], negated=not preds[0].negated), *preds[1:])


@v_args(meta=True)
class Build(Transformer):
    """A parse tree to items: each rule's method gives its meaning."""

    def __init__(self, text: str) -> None:
        super().__init__()
        self.text = text

    def _said(self, meta) -> str:
        return self.text[meta.start_pos : meta.end_pos] if not meta.empty else ""

    # -- the goal
    def start(self, meta, items):
        # "..., without knocking the cup over" is two items in one
        return tuple(i for x in items for i in (x if isinstance(x, tuple) else (x,)))

    def says(self, meta, c):
        subjects, *vps = c
        preds = tuple(p for vp in vps for p in vp)
        return Item(_nouns(subjects), preds)

    def says_bare(self, meta, c):
        return Item(_nouns(c[0]), c[1])

    def ditto(self, meta, c):
        return Item(_nouns(c[0]), None)

    def holds(self, meta, c):
        return Item(_nouns(c[0]), (Pred("held"),))

    def holds_not(self, meta, c):
        return Item(_nouns(c[0]), (Pred("held", negated=True),))

    def empty(self, meta, c):
        everything = Noun("everything", None, "everything")
        return Item((everything,), (Pred("held", negated=True),))

    # -- verbs and what follows them
    def vp(self, meta, c):
        head, preds = c
        if head == "no":
            return _first_negated(preds)
        if head == "stand":
            return (Pred("upright", implied=True), *preds)
        return preds

    def stands(self, meta, c):
        return (Pred("upright"),)

    def yes(self, meta, c):
        return "yes"

    def no(self, meta, c):
        return "no"

    def stand(self, meta, c):
        return "stand"

    def complements(self, meta, c):
        return tuple(p for comp in c for p in comp)

    def on_table(self, meta, c):
        return (Pred("on", "table"),)

    def on(self, meta, c):
        return (Pred("on", _nouns(c[0])),)

    def on_end(self, meta, c):
        side = c[0]
        host = _nouns(c[1]) if len(c) > 1 else ()
        return (Pred("on_end", side, host=host),)

    def on_end_named(self, meta, c):
        host, side = c
        return (Pred("on_end", side, host=_nouns(host)),)

    def side(self, meta, c):
        return str(c[0])

    def table(self, meta, c):
        return "table"

    def off_table(self, meta, c):
        return (Pred("gone"),)

    def off(self, meta, c):
        return (Pred("on", _nouns(c[0]), negated=True),)

    def left_of(self, meta, c):
        return (Pred("left_of", _nouns(c[0])),)

    def right_of(self, meta, c):
        return (Pred("right_of", _nouns(c[0])),)

    def in_front_of(self, meta, c):
        return (Pred("in_front_of", _nouns(c[0])),)

    def behind(self, meta, c):
        return (Pred("behind", _nouns(c[0])),)

    def out_from_behind(self, meta, c):
        return (Pred("behind", _nouns(c[0]), negated=True),)

    def gone(self, meta, c):
        return (Pred("gone"),)

    def visible(self, meta, c):
        return (Pred("gone", negated=True),)

    def upright(self, meta, c):
        return (Pred("upright"),)

    def tipped(self, meta, c):
        return (Pred("tipped"),)

    def held(self, meta, c):
        return (Pred("held"),)

    def across(self, meta, c):
        return (Pred("lies", "across"),)

    def lengthwise(self, meta, c):
        return (Pred("lies", "lengthwise"),)

    def not_(self, meta, c):
        return _negate(c[0])

    def neither(self, meta, c):
        return _negate(c[0]) + _negate(c[1])

    # -- instructions: each the state it asks for
    def do(self, meta, c):
        subjects, preds = c[0]
        return Item(subjects, preds, instruction=True)

    def dont(self, meta, c):
        subjects, preds = c[0]
        return Item(subjects, _negate(preds), instruction=True)

    def without(self, meta, c):
        (subjects, preds), (others, avoided) = c
        # Two items in one: the "without" part is said of its own objects.
        return (Item(subjects, preds, True), Item(others, _negate(avoided), True))

    def put(self, meta, c):
        return _nouns(c[0]), c[1]

    def put_standing(self, meta, c):
        return _nouns(c[0]), (Pred("upright", implied=True), *c[1])

    def stand_up(self, meta, c):
        return _nouns(c[0]), (Pred("upright"),)

    def take(self, meta, c):
        return _nouns(c[0]), (Pred("held", passing=True),)

    def tip(self, meta, c):
        return _nouns(c[0]), (Pred("tipped"),)

    def rid(self, meta, c):
        return _nouns(c[0]), (Pred("gone"),)

    def ing_off(self, meta, c):
        return _nouns(c[0]), (Pred("on", _nouns(c[1])),)

    # -- noun phrases
    def all_of(self, meta, c):
        return tuple(n for x in c for n in _nouns(x))

    def neither_of(self, meta, c):
        return tuple(replace(n, denied=True) for x in c for n in _nouns(x))

    def nps(self, meta, c):
        return c[0]

    def _noun(self, meta, c, quantity: str) -> Noun:
        kind: str | None = None
        colour: str | None = None
        order: list[str] = []
        restrict: list[Pred] = []
        nearest: list[Noun] = []
        from_right = False
        for x in c:
            if isinstance(x, str):  # a number word: "the two cups"
                quantity = x
            elif x and isinstance(x[0], Pred):  # a relative reference, said after the noun
                restrict.extend(x)
            elif x[0] == "mod":
                colour = x[1] if x[1] in COLOUR_WORDS else colour
                order += [] if x[1] in COLOUR_WORDS else [x[1]]
            elif x[0] == "noun":
                kind = KINDS[x[1]]
            elif x[0] == "place":
                order.append(x[1])
            elif x[0] == "from":
                from_right = x[1] == "right"
            elif x[0] == "nearest":
                nearest.extend(x[1])
        return Noun(
            self._said(meta),
            kind,
            quantity,
            colour,
            tuple(order),
            from_right,
            tuple(restrict),
            tuple(nearest),
            denied=quantity == "none",
        )

    def one(self, meta, c):
        return self._noun(meta, c, "one")

    def some(self, meta, c):
        return self._noun(meta, c, "some")

    def every(self, meta, c):
        return self._noun(meta, c, "every")

    def both(self, meta, c):
        return self._noun(meta, c, "both")

    def counted(self, meta, c):
        return self._noun(meta, c, "every")

    def none(self, meta, c):
        return self._noun(meta, c, "none")

    def it(self, meta, c):
        return Noun("it", None, "it")

    def them(self, meta, c):
        return Noun(self._said(meta), None, "them")

    def everything(self, meta, c):
        return Noun("everything", None, "everything")

    def number(self, meta, c):
        return str(c[0])

    def mod(self, meta, c):
        return ("mod", str(c[0]))

    def noun(self, meta, c):
        return ("noun", str(c[0]))

    def nouns(self, meta, c):
        return ("noun", str(c[0])[:-1])  # "cups": "cup"

    def place(self, meta, c):
        return ("place", next(PLACES[str(w)] for w in reversed(c) if str(w) in PLACES))

    def counted_from(self, meta, c):
        return ("from", c[0])

    def nearest(self, meta, c):
        return ("nearest", _nouns(c[0]))

    def that(self, meta, c):
        head, preds = c
        preds = _first_negated(preds) if head == "no" else preds
        return preds
