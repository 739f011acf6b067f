"""What a parse of a goal says: noun phrases, relations and items, before the scene resolves them.

`grammar.py` parses a sentence; `Build` turns each parse tree into `Item`s, one method per rule
of the grammar, each giving that rule's meaning: a complement the relation it states, an
instruction the state it asks for ("knock the cup over": the cup tipped over), a noun phrase
what it says of the objects it names (`nouns.py`: kind, colour, order words, relative
references, whose an object is).
"""

from __future__ import annotations

from dataclasses import replace

from lark import v_args

from afford.words.clauses import Item, Noun, Pred, Unread
from afford.words.lexicon import TURNS
from afford.words.nouns import NounPhrases, as_nouns, first_negated


# ---------------------------------------------------------------------------- meaning
def _negate(preds: tuple[Pred, ...]) -> tuple[Pred, ...]:
    return tuple(replace(p, negated=not p.negated) for p in preds)


def _no_longer(preds: tuple[Pred, ...]) -> tuple[Pred, ...]:
    """Read "no longer" as "off": "no longer on the table" is gone, as "off the table" is (the
    taught phrasing), and "no longer" before anything else denies it."""
    return tuple(
        Pred("gone") if p.relation == "on" and p.other == "table" and not p.negated else _negate((p,))[0]
        for p in preds
    )


@v_args(meta=True)
class Build(NounPhrases):
    """A parse tree to items: each rule's method gives its meaning (a noun phrase's,
    `NounPhrases`')."""

    # -- the goal
    def start(self, meta, items):
        # "..., without knocking the cup over" is two items in one
        said: list[Item] = []
        for i in (i for x in items for i in (x if isinstance(x, tuple) else (x,))):
            if i == ":":  # "swap them: the ball on the block and ...": what follows names them
                said[-1] = replace(said[-1], explained=True)
            else:
                said.append(i)
        return tuple(said)

    def colon(self, meta, c):
        return ":"

    def says(self, meta, c):
        subjects, *vps = c
        preds = tuple(p for vp in vps for p in vp)
        return Item(as_nouns(subjects), preds)

    def says_bare(self, meta, c):
        return Item(as_nouns(c[0]), c[1])

    def topic(self, meta, c):
        # "the far cup, knock it over": named first, for the pronoun of what follows
        return Item(as_nouns(c[0]), (), instruction=True)

    def topic_which(self, meta, c):  # "whichever cup is further back, ..."
        return Item((self._noun(meta, c, "one"),), (), instruction=True)

    def purpose_first(self, meta, c):
        # "so that the cup ends up in front of the block, move it onto the table"
        return tuple(c)  # in the order said: the command's "it" names what the state named

    def vcomp(self, meta, c):
        return c[0]

    def unwanted(self, meta, c):  # "I don't want the ball on the support": its state denied
        if c[0].preds is None or len(c[0].preds) != 1:  # "not X and Y" is not "not X, not Y"
            raise Unread("'I do not want' denies one state at a time", [], None)
        return replace(c[0], preds=_negate(c[0].preds))

    def says_asked(self, meta, c):  # "can the cup go behind the ball?"
        return Item(as_nouns(c[0]), c[1])

    def caused(self, meta, c):
        # "it sweeps the cup off the table": a state of the object the subject acts on
        return Item(as_nouns(c[1]), c[2])

    def caused_tip(self, meta, c):
        return Item(as_nouns(c[1]), (Pred("tipped"),))

    def ditto(self, meta, c):
        return Item(tuple(n for x in c for n in as_nouns(x)), None)

    def holds(self, meta, c):
        return Item(as_nouns(c[0]), (Pred("held"),))

    def holds_not(self, meta, c):
        return Item(as_nouns(c[0]), (Pred("held", negated=True),))

    def empty(self, meta, c):
        everything = Noun("everything", None, "everything")
        return Item((everything,), (Pred("held", negated=True),))

    # -- verbs and what follows them
    def vp(self, meta, c):
        head, preds = c
        if head == "no":
            return first_negated(preds)
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
        return (Pred("on", as_nouns(c[0])),)

    def on_end(self, meta, c):
        side = c[0]
        host = as_nouns(c[1]) if len(c) > 1 else ()
        return (Pred("on_end", side, host=host),)

    def on_end_named(self, meta, c):
        host, side = c
        return (Pred("on_end", side, host=as_nouns(host)),)

    def side(self, meta, c):
        return str(c[0])

    def table(self, meta, c):
        return "table"

    def off_table(self, meta, c):
        return (Pred("gone"),)

    def source(self, meta, c):
        # "move the ball from the support onto the block": where it starts, kept only where
        # nothing later in the sentence puts it somewhere
        return (Pred("on", as_nouns(c[0]), negated=True, passing=True, source=True),)

    def on_other_end(self, meta, c):
        return (Pred("on_end", "other", host=as_nouns(c[0]) if c else ()),)

    def off(self, meta, c):
        return (Pred("on", as_nouns(c[0]), negated=True),)

    def left_of(self, meta, c):
        return (Pred("left_of", as_nouns(c[0])),)

    def right_of(self, meta, c):
        return (Pred("right_of", as_nouns(c[0])),)

    def in_front_of(self, meta, c):
        return (Pred("in_front_of", as_nouns(c[0])),)

    def behind(self, meta, c):
        return (Pred("behind", as_nouns(c[0])),)

    def out_from_behind(self, meta, c):
        return (Pred("behind", as_nouns(c[0]), negated=True),)

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
        return (Pred("between", as_nouns(c[0])),)

    def where(self, meta, c):
        return (Pred("on", (Noun(self._said(meta), None, "host", bears=as_nouns(c[0])),)),)

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
        return Item(as_nouns(c[0]), _negate(c[1]), instruction=True)

    def purpose_only(self, meta, c):
        # "move the ball so that it is behind the cup": the purpose is the whole goal
        return (Item(as_nouns(c[0]), (), instruction=True), c[1])

    def purpose(self, meta, c):
        # "turn the block so that it points away": the instruction and the state it is for
        return tuple(c)

    def without(self, meta, c):
        (subjects, preds), (others, avoided) = c
        # Two items in one: the "without" part is said of its own objects.
        return (Item(subjects, preds, True), Item(others, _negate(avoided), True))

    def put(self, meta, c):
        return as_nouns(c[0]), c[1]

    def put_standing(self, meta, c):
        return as_nouns(c[0]), (Pred("upright", implied=True), *c[1])

    def stand_up(self, meta, c):
        return as_nouns(c[0]), (Pred("upright"),)

    def put_down(self, meta, c):
        return as_nouns(c[0]), (Pred("on", "table"),)

    def turn(self, meta, c):
        return as_nouns(c[0]), (Pred("turn", c[1] if len(c) > 1 else 90),)

    def turn_with(self, meta, c):  # "make a quarter turn with the block"
        return as_nouns(c[-1]), (Pred("turn", c[0] if len(c) > 1 else 90),)

    def swap(self, meta, c):
        return tuple(n for x in c for n in as_nouns(x)), (Pred("swap"),)

    def take(self, meta, c):
        return as_nouns(c[0]), (Pred("held", passing=True),)

    def hold(self, meta, c):  # "keep holding it": held at the end, not on the way
        return as_nouns(c[0]), (Pred("held"),)

    def release(self, meta, c):
        return as_nouns(c[0]), (Pred("held", negated=True),)

    def tip(self, meta, c):
        return as_nouns(c[0]), (Pred("tipped"),)

    def clear(self, meta, c):  # "clear the block": what rests on it at the start is off it
        hosts = as_nouns(c[0])
        said = "everything on " + " and ".join(n.words for n in hosts)
        return (Noun(said, None, "every", restrict=(Pred("on", hosts),)),), (Pred("on", hosts, negated=True),)

    def rid(self, meta, c):
        return as_nouns(c[0]), (Pred("gone"),)

    def ing_off(self, meta, c):
        return as_nouns(c[0]), (Pred("on", as_nouns(c[1])),)
