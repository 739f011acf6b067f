"""What a parse of a goal says: noun phrases, relations and items, before the scene resolves them.

`grammar.py` parses a sentence; `Build` turns each parse tree into `Item`s, one method per rule
of the grammar, each giving that rule's meaning: a complement the relation it states, an
instruction the state it asks for ("knock the cup over": the cup tipped over), a noun phrase
what it says of the objects it names (kind, colour, order words, relative references).
"""

from __future__ import annotations

from dataclasses import replace

from lark import Transformer, v_args

from afford.words.clauses import Item, Noun, Pred
from afford.words.lexicon import COLOUR_WORDS, DETERMINERS, KINDS, PLACES, PLURAL_NOUNS, TURNS


# ---------------------------------------------------------------------------- meaning
def _nouns(x) -> tuple[Noun, ...]:
    return x if isinstance(x, tuple) else (x,)


def _negate(preds: tuple[Pred, ...]) -> tuple[Pred, ...]:
    return tuple(replace(p, negated=not p.negated) for p in preds)


def _no_longer(preds: tuple[Pred, ...]) -> tuple[Pred, ...]:
    """Read "no longer" as "off": "no longer on the table" is gone, as "off the table" is (the
    taught phrasing), and "no longer" before anything else denies it."""
    return tuple(
        Pred("gone") if p.relation == "on" and p.other == "table" and not p.negated else _negate((p,))[0]
        for p in preds
    )


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
        return Item(tuple(n for x in c for n in _nouns(x)), None)

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
        if head == "no longer":
            return _no_longer(preds[:1]) + preds[1:]
        if head == "stand":
            return (Pred("upright", implied=True), *preds)
        return preds

    def stands(self, meta, c):
        return (Pred("upright"),)

    def yes(self, meta, c):
        return "yes"

    def no(self, meta, c):
        return "no"

    def nolonger(self, meta, c):
        return "no longer"

    def vp_do(self, meta, c):
        return c[-1]

    def vp_dont(self, meta, c):
        return _negate(c[-1])

    def no_longer(self, meta, c):
        return _no_longer(c[0])

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

    def source(self, meta, c):
        # "move the ball from the support onto the block": where it starts, kept only where
        # nothing later in the sentence puts it somewhere
        return (Pred("on", _nouns(c[0]), negated=True, passing=True, source=True),)

    def on_other_end(self, meta, c):
        return (Pred("on_end", "other", host=_nouns(c[0]) if c else ()),)

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

    def between(self, meta, c):
        return (Pred("between", _nouns(c[0])),)

    def where(self, meta, c):
        return (Pred("on", (Noun(self._said(meta), None, "host", bears=_nouns(c[0])),)),)

    def turned(self, meta, c):
        return (Pred("turn", c[0] if c else 90),)

    def angle(self, meta, c):
        return next(int(x) for x in c if isinstance(x, int))

    def half_turn(self, meta, c):
        return 180

    def degrees(self, meta, c):
        word = str(c[0])
        return TURNS[word] if word in TURNS else int(word)

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

    def keep_from(self, meta, c):
        return Item(_nouns(c[0]), _negate(c[1]), instruction=True)

    def purpose_only(self, meta, c):
        # "move the ball so that it is behind the cup": the purpose is the whole goal
        return (Item(_nouns(c[0]), (), instruction=True), c[1])

    def purpose(self, meta, c):
        # "turn the block so that it points away": the instruction and the state it is for
        return tuple(c)

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

    def put_down(self, meta, c):
        return _nouns(c[0]), (Pred("on", "table"),)

    def turn(self, meta, c):
        return _nouns(c[0]), (Pred("turn", c[1] if len(c) > 1 else 90),)

    def swap(self, meta, c):
        return tuple(n for x in c for n in _nouns(x)), (Pred("swap"),)

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

    def shared(self, meta, c):
        return ("mods", c)

    def shared_noun(self, meta, c):
        """For "the left and the right cup": one noun said once for several sets of words."""
        groups = [x[1] for x in c if isinstance(x, tuple) and x[0] == "mods"]
        rest = [x for x in c if not (isinstance(x, tuple) and x[0] == "mods")]
        noun = next(x for x in rest if isinstance(x, tuple) and x[0] == "noun")
        last = [x for x in rest if isinstance(x, tuple) and x[0] == "mod"]
        out = []
        for mods in [*groups, last]:
            said = " ".join(["the", *(m[1] for m in mods), noun[1]])
            out.append(replace(self._noun(meta, [*mods, noun], "one"), words=said))
        posts = [x for x in rest if not (isinstance(x, tuple) and x[0] in ("mod", "noun"))]
        if posts:
            out[-1] = replace(out[-1], restrict=self._noun(meta, [noun, *posts], "one").restrict)
        return tuple(out)

    def neither_of(self, meta, c):
        return tuple(replace(n, denied=True) for x in c for n in _nouns(x))

    def nps(self, meta, c):
        return c[0]

    def _noun(self, meta, c, quantity: str, other: bool = False) -> Noun:
        kind: str | None = None
        colour: str | None = None
        order: list[str] = []
        restrict: list[Pred] = []
        nearest: list[Noun] = []
        bears: list[Noun] = []
        excluded: list[Noun] = []
        bare = False
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
            elif x[0] == "bare":
                bare = True
            elif x[0] == "bears":
                bears.extend(x[1])
            elif x[0] == "except":
                excluded.extend(x[1])
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
            bare=bare,
            other=other,
            excluded=tuple(excluded),
            bears=tuple(bears),
        )

    def one(self, meta, c):
        return self._noun(meta, c, "one")

    def det(self, meta, c):
        return ("det", " ".join(str(w) for w in c))

    def _determined(self, meta, c, plural: bool) -> Noun:
        said = next(x[1] for x in c if isinstance(x, tuple) and x[0] == "det")
        words = said.split()
        key = " ".join(w for w in words if w not in ("two", "three"))
        counted = [w for w in words if w in ("two", "three")]
        quantity = counted[0] if counted and plural else DETERMINERS.get(key, ("one", "every"))[int(plural)]
        rest = [x for x in c if not (isinstance(x, tuple) and x[0] == "det")]
        return self._noun(meta, rest, quantity, other=key == "the other")

    def np_one(self, meta, c):
        return self._determined(meta, c, plural=False)

    def np_many(self, meta, c):
        return self._determined(meta, c, plural=True)

    def other_one(self, meta, c):
        return self._noun(meta, c, "one", other=True)

    def other_all(self, meta, c):
        return self._noun(meta, c, "every", other=True)

    def except_(self, meta, c):
        return ("except", _nouns(c[0]))

    def bears(self, meta, c):
        return ("bears", _nouns(c[0]))

    def bare(self, meta, c):
        return ("bare",)

    def viewer_near(self, meta, c):
        return ("place", "front")

    def viewer_far(self, meta, c):
        return ("place", "back")

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
        word = str(c[0])
        return ("noun", PLURAL_NOUNS.get(word, word[:-1]))  # "cups": "cup"

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
