"""Noun phrases: how a goal names objects (the grammar's rules for them, `NOUN_PHRASES`) and
what each name says of the objects it picks out (`NounPhrases`, the part of a parse's meaning
built from them): kind, colour, order words, relative references, whose an object is.

`grammar.py` joins these rules to the rules of states and instructions; `parses.Build` gives
the meaning of a whole parse, its noun phrases by the methods here; `reference.py` resolves
them in a scene.
"""

from __future__ import annotations

from dataclasses import replace

from lark import Transformer, v_args

from afford.words.clauses import Noun, Pred
from afford.words.lexicon import COLOUR_WORDS, DETERMINERS, KINDS, PLACES, PLURAL_NOUNS


def as_nouns(x) -> tuple[Noun, ...]:
    """A noun phrase's parse as the nouns it names: one, or those of a list."""
    return x if isinstance(x, tuple) else (x,)


def first_negated(preds: tuple[Pred, ...]) -> tuple[Pred, ...]:
    """A negative verb ("does not sit", "should not be") denies the complement that follows it,
    as "not" does: "the cup should not be upright on the block" is "not upright, on the block"."""
    return (replace(preds[0], negated=not preds[0].negated), *preds[1:])


NOUN_PHRASES = r"""
nps: np
   | np ("," np)* ","? "and" np          -> all_of
   | "both" np "and" np                  -> all_of
   | np "as" "well" "as" np              -> all_of
   | "neither" np "nor" np               -> neither_of
   | _the shared ("," _the? shared)* ","? "and" _the? _mods (noun | nouns) _posts -> shared_noun
shared: mod+
np: det _mods noun _posts                -> np_one
  | det _mods nouns _posts               -> np_many
  | _mods noun _posts                    -> one
  | _mods nouns _posts                   -> every
  | "the" "other" number _posts          -> other_all
  | "the" "others"                       -> other_all
  | "it"                                 -> it
  | "them"                               -> them
  | ("them" | "they") ("both" | "all")   -> them
  | ("both" | "all") "of" "them"         -> them
  | "they"                               -> them
  | "everything"                         -> everything
  | _the _mods noun "'s" _mods noun _posts  -> owned_one
  | _the _mods noun "'s" _mods nouns _posts -> owned_many
// the determiner says how many the noun names (`lexicon.DETERMINERS`), and whose they are
!det: "neither" | "either" | "the" | "this" | "that" | "my" | "a" | "an" | "one" "of" "the" | "any" | "every"
    | "each" | "all"
    | "all" "the" | "all" "of" "the" | "each" "of" "the" | "any" "of" "the" | "both" | "both" "the"
    | "both" "of" "the" | "the" number | "all" number | number | "no" | "none" "of" "the" | "the" "other"
    | "the" "other" number | "its" | "their"
_the: "the" | "this" | "that" | "my"
_a: "a" | "an" | "one" "of" "the" | "any"
_every: "every" | "each"
_all: "all" | "all" "the" | "all" "of" "the" | "each" "of" "the" | "any" "of" "the"
_both: "both" | "both" "the" | "both" "of" "the"
!number: "two" | "three"
_mods: (mod | bare)*
bare: "empty" | "free" | "bare" | "unoccupied" | "vacant"
!mod: "blue" | "red" | "black" | "yellow" | "left" | "right" | "middle" | "mid" | "centre" | "center"
    | "leftmost"
    | "rightmost" | "first" | "second" | "third" | "fourth" | "last" | "front" | "back" | "rear" | "near"
    | "far" | "nearest" | "farthest" | "furthest" | "closest" | "left" "hand" | "right" "hand" | "central"
    | "outer" | "outside" | "outermost"
    | "nearer" | "closer" | "farther" | "further"
!noun: "cup" | "mug" | "ball" | "sphere" | "support" | "pillar" | "pedestal" | "block" | "brick" | "plank"
     | "beam" | "bar" | "board" | "slab" | "post" | "stand" | "column" | "pole" | "cylinder" | "glass"
     | "marble" | "one" | "thing" | "object"
!nouns: "cups" | "mugs" | "balls" | "spheres" | "supports" | "pillars" | "pedestals" | "blocks" | "bricks"
      | "planks" | "beams" | "bars" | "boards" | "slabs" | "posts" | "stands" | "columns" | "poles"
      | "cylinders" | "glasses" | "marbles" | "ones" | "things" | "objects"
_posts: post*
?post: _left_of np                       -> left_of
    | _right_of np                       -> right_of
    | _front_of np                       -> in_front_of
    | _behind np                         -> behind
    | _on np                             -> on
    | _on table                          -> on_table
    | _that head complements             -> that
    | (_that "is")? _near np             -> nearest
    | (_that "is")? _farthest np         -> farthest
    | "with" "nothing" ("on" "it" | "on" "top" | "on" "top" "of" "it")?  -> bare
    | _that _bearing "nothing" ("on" "it" | "on" "top")?               -> bare
    | _that "is" bare
    | (_that "is")? _closest _viewer     -> viewer_near
    | (_that "is")? ("further" | "farther") "back"      -> viewer_far
    | (_that "is")? ("further" | "farther") "forward"   -> viewer_near
    | (_that "is")? _farthest _viewer    -> viewer_far
    | _except nps                        -> except_
    | _that? np _rests_on                -> bears
    | "where" np _was                    -> bears
    | "with" np ("on" "it" | "on" "top" | "on" "top" "of" "it")?         -> bears
    | _that? _bearing np ("on" "it" | "on" "top")?                      -> bears
    | _under np                          -> bears
    | "from" np                          -> on
    | place
    | "from" "the" side                  -> counted_from
_that: "that" | "which"
_closest: "nearest" | "nearest" "to" | "closest" "to" | "nearer" "to" | "closer" "to" | "next" "to"
_farthest: ("farthest" | "furthest" | "farther" | "further" | "far") "away"? "from" | "away" "from"
_bearing: "has" | "holds" | "carries" | "supports" | "holding" | "carrying" | "supporting" | "bearing"
        | "having"
_except: "but" | "except" | "except" "for" | "other" "than" | "apart" "from" | "besides" | "save"
       | "excluding"
_rests_on: _rest_verb "on" | _rest_verb "on" "top" "of" | _rest_verb "upon"
_rest_verb: "is" | "was" | "sits" | "sat" | "rests" | "stands" | "lies" | "is" "sitting" | "is" "resting"
          | "is" "standing" | "is" "lying"
_near: "nearest" | "nearest" "to" | "closest" "to" | "next" "to" | "beside" | "near" | "by"
!place: "in" "the" ("middle" | "centre" | "center") "of" ("the" number | "them" | "the" "row" | "all" number)
      | "on" "the" "left" | "on" "the" "right" | "to" "the" "left" | "to" "the" "right"
            | "in" "the" "middle" | "in" "the" "centre" | "in" "the" "center" | "at" "the" "front"
            | "at" "the" "back" | "in" "front" | "at" "the" "left" | "at" "the" "right"
            | "on" "the" "far" "left" | "on" "the" "far" "right" | "on" "the"? "left" "side"
            | "on" "the"? "right" "side"
"""


@v_args(meta=True)
class NounPhrases(Transformer):
    """The meaning of each noun-phrase rule of a parse tree."""

    def __init__(self, text: str) -> None:
        super().__init__()
        self.text = text

    def _said(self, meta) -> str:
        return self.text[meta.start_pos : meta.end_pos] if not meta.empty else ""

    def all_of(self, meta, c):
        return tuple(n for x in c for n in as_nouns(x))

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
        return tuple(replace(n, denied=True) for x in c for n in as_nouns(x))

    def nps(self, meta, c):
        return c[0]

    def _noun(self, meta, c, quantity: str, other: bool = False) -> Noun:
        kind: str | None = None
        colour: str | None = None
        order: list[str] = []
        restrict: list[Pred] = []
        nearest: list[Noun] = []
        farthest: list[Noun] = []
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
            elif x[0] == "farthest":
                farthest.extend(x[1])
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
            farthest=tuple(farthest),
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
        noun = self._noun(meta, rest, quantity, other=key == "the other")
        if key in ("its", "their"):  # whose: found by the clause (`reference.py`)
            return replace(noun, owner=(Noun(key, None, "it" if key == "its" else "them"),))
        return noun

    def np_one(self, meta, c):
        return self._determined(meta, c, plural=False)

    def np_many(self, meta, c):
        return self._determined(meta, c, plural=True)

    def _owned(self, meta, c, quantity: str) -> Noun:
        """The owner's words up to its noun ("the ball's post"), then the owned one's."""
        at = next(i for i, x in enumerate(c) if isinstance(x, tuple) and x[0] == "noun") + 1
        owner = self._noun(meta, c[:at], "one")
        said = owner.words.split(" 's ")[0]
        return replace(self._noun(meta, c[at:], quantity), owner=(replace(owner, words=said),))

    def owned_one(self, meta, c):
        return self._owned(meta, c, "one")

    def owned_many(self, meta, c):
        return self._owned(meta, c, "every")

    def other_one(self, meta, c):
        return self._noun(meta, c, "one", other=True)

    def other_all(self, meta, c):
        return self._noun(meta, c, "every", other=True)

    def except_(self, meta, c):
        return ("except", as_nouns(c[0]))

    def bears(self, meta, c):
        return ("bears", as_nouns(c[0]))

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
        return ("nearest", as_nouns(c[0]))

    def farthest(self, meta, c):
        return ("farthest", as_nouns(c[0]))

    def that(self, meta, c):
        head, preds = c
        preds = first_negated(preds) if head == "no" else preds
        return preds
