"""The grammar of goals: what a person may say to the robot, parsed with lark.

A goal is one or more items joined by "and", commas, "but" or "then". An item is a state ("the
cup is on the block", "both balls are gone", "the cup stands upright on the block"), an
instruction ("put the red ball on the block", "knock the cup over", "hand me the ball"), or a
state after a lead-in ("make sure the cup is upright"). `read` gives every parse of a sentence
as `Item`s whose noun phrases are not yet resolved: what they refer to depends on the scene
(`reference.py`), and so does which of two parses is meant.

The grammar is written over whole words: a sentence is first normalised (`earley.words`) and
each word is one token, so that no word is ever matched as part of another. The meaning of a
parse is in its rule names: a complement's name is the relation it states ("on", "gone",
"left_of"), an instruction's the state it asks for (`parses.py` gives each its meaning).

Where what people say could mean two things, one rule decides, whatever the sentence:

- A sequence ("first X, then Y", "X and then Y", "X, after that Y") asks for the state after
  all of it: the clauses of its items together. The order is not kept: the planner is given
  the clauses as one goal, and success is all of them holding at the end. "Then the ball" (an
  item of noun phrases alone) says the item before of them: "put the cup on the block, then
  the ball" puts both there.
- A purpose ("turn the block so that it points away from the robot", "... until ...") adds its
  state to the instruction's; after a verb that asks for nothing by itself ("move the ball so
  that it is behind the cup") it is the whole goal.
- "Off the table", "no longer on the table", "on the floor" mean gone, whatever the verb ("get
  the cup off the table" too): the taught phrasings of gone say so ("the ball is off the
  table", "the ball is no longer on the table"), and one phrase reads one way. "Not on the
  table" is the weaker not on(table), which a cup on the block also meets. "No longer" before
  anything else is "not" ("no longer upright"), and "off" anything else is not on it.
- "Don't", "never", "without" and "keep ... from" deny the state the instruction asks for:
  "don't knock the cup over" is not tipped, rather than upright (a cup pushed off the table is
  neither).
- "From" after a moved object names where it starts ("move the ball from the post onto the
  block"), the one it rests on where the name fits several, and asks for nothing where the
  sentence puts it somewhere; "remove the ball from the support" is not on it.
- A turn ("turn the block", "rotate the block 90 degrees", "a quarter turn", "around", "give
  the block a half turn") is said of the block's lie at the start: a quarter turn, or a turn
  with no angle, the other lie; a half turn the same; other angles are refused (`derived.py`).
- A purpose after a verb that asks a state of its own ("turn the block so that both balls roll
  off") adds to it: the reading where the verb asks nothing is less likely meant. A purpose
  may end in a verb of a state ("so that the cup falls over": tipped; "disappears": gone).
- "Clear (off) X", "empty X": what rests on X at the start is not on it, each cup, ball or
  block on it.
- "Would you mind VERBing ..." is "please VERB ..."; courtesies stack ("could you please").
- "Put X down" alone is X on the table; "down" and "back" before a place are read past ("put
  the ball back on the table").
- Verbs whose goal is a state: "make/let X disappear, fall over, fall off the table", "X should
  disappear"; "balance X on Y" is on.
- Names may describe an object by the start scene: "the other support" (not the one named or
  rested on), "the empty support", "the support the ball is on", "the post where the ball was",
  "every cup except the middle one", "the cup nearest the robot" (the front one: the robot
  looks from the camera's side), "where the ball was", "between the cups"; a noun said once for
  two ("the left and the right cup"). "The other one" takes its kind from its own role, else
  from the subject's ("put the left mug to the right of the other one": the other cup).
- "Its", "their" and "the ball's" before a noun name the one of that noun that rests on the
  owner or that the owner rests on, at the start ("take the ball down from its post"). "Its"
  is the clause's subject's where that has one, else of what was named before, most recent
  first, else of the one object of the scene that has one; "their" of what was said last.
- "Too", "as well" and "also" add nothing ("put the left cup on the block too").
- A state said beside an instruction ("... while you put the ball on it", "..., keeping the
  cup upright", "while holding the ball, ...") is part of the goal, as a purpose is. "Keep
  holding X" asks for X held at the end; "let go of X", "release X", "drop X" for X not held,
  and a pick-up said before them is on the way.
- What follows a colon says what the pronouns of the item before it name ("swap them: the
  ball on the block and the cup on the support").
- A misspelt word is read as a known word a single slip away (a letter dropped, added,
  changed, or two swapped: "blok", "teh", "lenghtwise") where, of the sentence's spellings so
  made, exactly one reads ("fron" is "front" in "in fron of the cup", not "from"); the reading
  shown says which word was read. Otherwise it is refused, with the sentence spelt right
  offered. Chat spellings ("u", "pls") are spelt out as contractions are.
"""

from __future__ import annotations

import functools
import itertools

from lark import Lark
from lark.exceptions import UnexpectedEOF, UnexpectedInput, UnexpectedToken, VisitError
from lark.visitors import CollapseAmbiguities

from afford.words import earley, typed
from afford.words.clauses import Unread
from afford.words.earley import words
from afford.words.instructions import INSTRUCTIONS
from afford.words.nouns import NOUN_PHRASES
from afford.words.parses import Build, Item

SENTENCES = r"""
start: (_while_word? kept "," | _while _item ",")? _item (_join _later | _but _item | kept)*
_join: "and" | "," | "," "and" | _then | "and" _then | "," _then | "," "and" _then | _while | colon
     | ","? "and"? "while" "you" "are" "at" "it" ","?

_while: ","? _while_word "you"?
_while_word: "while" | "whilst"
colon: ":"
_but: "but" | "," "but"
_then: ("then" | "after" "that" | "afterwards" | "next" | "finally" | "and" "finally") ","?
_later: _item | ditto | kept
ditto: dnp ("and" dnp)? _after?
dnp: _the _mods noun                -> one
    | _the _mods nouns               -> every
    | _both _mods nouns              -> both
    | "the" "other" _mods noun       -> other_one
    | "the" "other" "one"            -> other_one
    | "it"                           -> it

_item: state _after? | command | _lead state _after? | purpose | unwanted
     | topic "," command
unwanted: _lead_not state _after?
_lead_not: "i" ("do" | "would") "not" ("want" | "like") | "i" "would" "rather" "not" "have"
// the object named first, then what to do with it: "the far cup, knock it over"
topic: _whichever? nps
     | _whichever _mods noun "is" post+   -> topic_which
_whichever: "whichever" | "which" "ever"
purpose: command _so_that state _after?
       | _polite* _put nps _out? _so_that state _after?  -> purpose_only
       | ("so" "that" | "in" "order" "that") state "," command   -> purpose_first
_out: "out" | "around" | "round"
_so_that: "so" | "so" "that" | "," "so" | "," "so" "that" | "such" "that" | "in" "order" "that"
        | "until"
_after: "any" "more" | "anymore" | "any" "longer" | "afterwards" | "in" "the" "end" | "at" "the" "end"
      | "again" | _too | "also"
_lead: "first" | "make" "sure" | "make" "sure" "that" | "ensure" | "ensure" "that" | "see" "that"
     | "i" "want" | "i" "want" "that" | "i" "would" "like" | "i" "need" | "i" "expect"
     | "the" "goal" "is" | "the" "goal" "is" "that" | "what" "i" "need" "is" | "what" "i" "want" "is"
     | "what" "i" "would" "like" "is" | "all" "i" "want" "is" | "all" "i" "need" "is" | "i" "would" "love"
     | "i" "would" "prefer" | "i" "would" "love" "to" "see" | "let" "'s" "have" | "let" "us" "have"
     | "i" "would" "like" "to" "have" | "i" "want" "to" "have" | "make" "it" "so" "that"
     | "i" "would" "like" "it" "if"
     | "make" "it" "so" | "is" "it" "possible" "to" "have" | "i" "want" "to" "see"
     | "i" "would" "like" "to" "see" | "let" "'s" "make" "sure"

// ------------------------------------------------------------------ states
state: nps _preds                    -> says
     | _ask nps _go_base complements -> says_asked
     | nps complements               -> says_bare
     | "so" _so nps                  -> ditto
     | "as" _so nps                  -> ditto
     | nps _too                      -> ditto
     | nps _so _too                  -> ditto
     | _holder _holds nps            -> holds
     | _holder _holds_not nps        -> holds_not
     | _holder _empty                -> empty
     | nps _placed complements       -> says_bare
     | nps _causes nps complements   -> caused
     | nps _causes nps "over"        -> caused_tip
// a question that asks for a state: "can the cup go behind the ball?"
_ask: "can" | "could" | "will" | "would"
_go_base: "go" | "be" | "end" "up" | "sit" | "rest" | "lie" | "stay" | "land"
_placed: "sitting" | "resting" | "lying" | "placed" | "put" | "set" | "positioned" | "perched" | "balanced"
       | "stacked" | "parked" | "moved" | "shifted" | "left" | "brought" | "taken" | "standing"
// a state brought about by its subject: "(so that) it sweeps the cup off the table"
_causes: "sweeps" | "pushes" | "knocks" | "throws" | "carries" | "takes" | "shoves" | "tips" | "brings"
       | "moves" | "sends" | "drags" | "flicks"
_so: "is" | "are" | "does" | "do"
_too: "too" | "as" "well"
_holder: "the" "gripper" | "the" "robot" | "the" "hand" | "the" "arm" | "you"
       | "the" "robot" "'s" "gripper" | "the" "robot" "'s" "hand"
_holds: "holds" | "hold" | "has" | "is" "holding" | "are" "holding" | "grips" | "is" "gripping"
      | "is" "carrying" | "carries" | _modal "hold" | _modal "be" "holding" | _modal "have"
_holds_not: "does" "not" "hold" | "do" "not" "hold" | "is" "not" "holding" | "are" "not" "holding"
          | "does" "not" "have" | _modal "not" "hold" | _modal "not" "be" "holding"
_empty: "is" "empty" | "holds" "nothing" | "is" "holding" "nothing" | _modal "be" "empty"
      | _modal "hold" "nothing" | "has" "nothing" | "is" "not" "holding" "anything"
      | "does" "not" "hold" "anything" | _modal "not" "hold" "anything"

_preds: vp (_and vp)*
_and: "and" | "," | "," "and" | "but"
vp: head complements
  | _stand                           -> stands
  | ("stay" | "stays" | "remain" | "remains") "up"  -> stands
  | _modal _stand_base               -> stands
  | _modal vstate                    -> vp_do
  | _modal "not" vstate              -> vp_dont
  | vstates                          -> vp_do
  | vstate                           -> vp_do
  | _do "not" vstate                 -> vp_dont
head: _pos                           -> yes
    | _modal "no" "longer" _be_base  -> nolonger
    | _stand                         -> stand
    | _modal _stand_base             -> stand
    | "to" _stand_base               -> stand
    | _neg                           -> no
_pos: _be | _have | _modal _be_base | _verb | _modal _verb_base | "to" _be_base | "to" _verb_base
_neg: _modal "not" _be_base | _do "not" _verb_base | _modal "not" _verb_base | "not" "to" _be_base
    | _do "not" _stand_base | _modal "not" _stand_base
_be: "is" | "are" | "is" "still" | "are" "still" | "has" "been" | "have" "been" | "is" "now"
   | "are" "now" | "was" | "were" | "are" "both" | "are" "all" | "both" "are" | "all" "are"
   | "gets" | "get" | "got" | "is" "getting" | "are" "getting"
_have: "has" | "have"
_be_base: "be" | "be" "still" | "end" "up" | "stay" | "remain" | "be" "left" | "get"
_verb: "runs" | "run" | "goes" | "go" | "lands" | "land" | "sits" | "sit" | "rests" | "rest" | "lies"
     | "lie" | "stays" | "stay" | "remains"
     | "remain" | "ends" "up" | "end" "up" | "points" | "point" | "falls" | "fall" | "fell"
     | "rolls" | "roll" | "rolled" | "sat" | "lay"
_verb_base: "sit" | "rest" | "lie" | "stay" | "remain" | "end" "up" | "point" | "fall" | "roll"
_stand: "stands" | "stand" | "stood"
_stand_base: "stand"
_modal: "should" | "must" | "has" "to" | "have" "to" | "needs" "to" | "need" "to" | "will"
      | "shall" | "ought" "to" | "is" "to" | "are" "to" | "should" "now" | "must" "now"
_do: "does" | "do" | "did"

complements: _particle? comp (_and? comp | "," _placed comp)*
_particle: "down" | "back" | "back" "down" | "down" "again"
comp: _on table                      -> on_table
    | _on nps                        -> on
    | _end_at? ("the" | "its")? side "hand"? "end" ("of" nps)?   -> on_end
    | _end_at nps side "end"         -> on_end_named
    | _end_at nps "'s" side "end"    -> on_end_named
    | _end_at ("the" | "its")? _opposite "end" ("of" nps)? -> on_other_end
    | "to" _across                   -> across
    | "to" _lengthwise               -> lengthwise
    | _on _ground                    -> off_table
    | _off table                     -> off_table
    | _off nps                       -> off
    | "from" table                   -> off_table
    | "from" nps                     -> source
    | _left_of nps                   -> left_of
    | _right_of nps                  -> right_of
    | _front_of nps                  -> in_front_of
    | _behind nps                    -> behind
    | "out" "from" "behind" nps      -> out_from_behind
    | _gone                          -> gone
    | _visible                       -> visible
    | _upright                       -> upright
    | _tipped                        -> tipped
    | _held                          -> held
    | _across                        -> across
    | _lengthwise                    -> lengthwise
    | "not" comp                     -> not_
    | "no" "longer" comp             -> no_longer
    | "in"? "between" nps            -> between
    | _under nps                     -> gone
    | "where" np _was                -> where
    | _turned angle                  -> turned
    | "neither" comp "nor" comp      -> neither
!side: "left" | "right"
_opposite: "other" | "opposite"
_under: "under" | "underneath" | "beneath" | "below"
_was: "was" | "is" | "were" | "are" | "used" "to" "be" | "stood" | "sat" | "lay" | "started" | "was" "before"
    | "is" "now" | "stands" | "sits" | "rests"
_turned: "turned" | "rotated" | "spun" | "twisted"
angle: "by"? degrees ("degrees" | "degree")?
     | "by"? "a" degrees "turn"?
     | "halfway"? "around"               -> half_turn
     | "halfway"? "round"                -> half_turn
!degrees: "30" | "45" | "60" | "90" | "120" | "135" | "180" | "270" | "360" | "ninety" | "quarter" | "half"
_viewer: "the" "robot" | "you" | "me" | "the" "camera" | "us" | "the" "viewer" | "the" "arm"
table: "the"? "table" | "the" ("edge" | "side") "of" "the" "table" | "the"? "tabletop"
     | "the" "table" "top" | "the" "table" "'s" "top"
_ground: "the" "floor" | "the" "ground"
_on: "on" | "onto" | "upon" | "atop" | "on" "top" "of" | "onto" "the" "top" "of" | "up" "on"
   | "up" "onto" | "on" "to" | "in" "place" "on" | "to" | "over" "to" | "across" "to" | "up" "to"
_end_at: _on | "at"
_off: "off" | "off" "of" | "fallen" "off" | "fell" "off" | "rolled" "off" | "knocked" "off"
    | "pushed" "off" | "thrown" "off" | "taken" "off" | "removed" "from" | "no" "longer" "on"
_left_of: "left" "of" | "to" "the" "left" "of" | "on" "the" "left" "of" | "on" "the" "left" "side" "of"
        | "to" "the" "left" "side" "of" | "at" "the" "left" "of"
_right_of: "right" "of" | "to" "the" "right" "of" | "on" "the" "right" "of"
         | "on" "the" "right" "side" "of" | "to" "the" "right" "side" "of" | "at" "the" "right" "of"
_front_of: "in" "front" "of" | ("nearer" | "closer") "to"? _viewer "than" | "before"
_behind: "behind" | "in" "back" "of" | "at" "the" "back" "of" | ("farther" | "further") "from" _viewer "than"
       | "farther" "back" "than" | "further" "back" "than" | ("farther" | "further") "away" "than"
_gone: "gone" | "hidden" | "out" "of" "sight" | "out" "of" "view" | "invisible" | "no" "longer" "there"
     | "no" "longer" "visible" | "away"
_visible: "visible" | "in" "sight" | "in" "view" | "still" "there" | "still" "visible"
_upright: "still" "up" | "still" "standing" | "still" "upright" | "upright" | "standing"
        | "standing" "up" | "the" "right" "way" "up" | "right" "side" "up"
        | "on" "its" "base" | "on" "its" "bottom" | "set" "upright" | "back" "up"
_tipped: "tipped" "over" | "tipped" | "knocked" "over" | "knocked" "down" | "toppled" | "toppled" "over"
       | "fallen" "over" | "fell" "over" | "on" "its" "side" | "lying" "on" "its" "side" | "lying" "down"
       | "upside" "down" | "turned" "over" | "tipped" "on" "its" "side" | "over" "on" "its" "side"
       | "tilted" | "tilted" "over" | "flipped" "over" | "overturned"
_held: "held" | "in" "the" "gripper" | "in" "the" "robot" "'s" "hand" | "in" "the" "robot" "'s" "gripper"
     | "in" "the" "hand" | "in" "hand" | "picked" "up" | "being" "held" | "gripped" | "grasped"
     | "lifted" | "lifted" "up" | "in" "its" "gripper" | "in" "the" "air" | "carried"
_across: "across" | "across" "the" "table" | "turned" "across" | "lying" "across" | "left" "to" "right"
       | "crosswise" | "crossways"
       | "from" "left" "to" "right" | "side" "to" "side"
_lengthwise: "lengthwise" | "lengthways" | "turned" "lengthwise" | "lying" "lengthwise" | "front" "to" "back"
           | "straight"? "away" "from" _viewer | "pointing" "straight"? "away" "from" _viewer
           | "pointing" "away" | "towards" _viewer
           | "toward" _viewer | "pointing" "towards" _viewer | "pointing" "toward" _viewer

// verbs that say a state without a complement: "make the ball disappear"
vstate: _vanish                           -> gone
      | _vend complements                  -> vcomp
      | _toppling                         -> tipped
      | _fall_off table                   -> off_table
      | _fall_off nps                     -> off
_vend: "end" "up" | "be" | "stay" | "sit" | "rest" | "lie" | "land" | "remain" | "wind" "up"
_toppling: _fall_verb "over" | _fall_verb "down" | "topple" | "topple" "over" | "tip" "over" | "tip" | "fall"
_fall_off: _fall_verb "off" | _fall_verb "off" "of"
_vanish: "disappear" | "vanish" | "go" "away" | "go" "missing" | "leave" "the" "table"
// the same, said of its subject: "so that the cup falls over", "until both balls roll off the table"
vstates: _vanishes                        -> gone
       | _topples                         -> tipped
       | _falls "off" "of"? table          -> off_table
       | _falls "off" "of"? nps            -> off
_topples: _falls "over" | _falls "down" | "topples" | "topples" "over" | "tips" "over" | "tips"
_falls: "falls" | "rolls" | "drops" | "slips" | "slides" | "tumbles" | "gets" "knocked"
_vanishes: "disappears" | "vanishes" | "goes" "away" | "goes" "missing" | "leaves" "the" "table"
// the same, said after "keep the cup from"
ving: _tipping                      -> tipped
    | _fall_ing "off" table          -> off_table
    | _fall_ing "off" nps            -> off
    | _vanishing                     -> gone
_tipping: _fall_ing "over" | _fall_ing "down" | "toppling" | "toppling" "over" | "tipping" "over" | "tipping"
        | "being" "knocked" "over" | "getting" "knocked" "over"
_vanishing: "disappearing" | "vanishing"
_fall_ing: "falling" | "rolling" | "dropping" | "slipping" | "sliding" | "tumbling"
_keep: "keep" | "stop" | "prevent"
_fall_verb: "fall" | "roll" | "drop" | "slip" | "slide" | "tumble" | "get" "knocked" | "be" "knocked"

// a state said beside an instruction: "..., keeping the cup upright", "while holding the ball"
kept: _keeping nps "still"? _placed? complements  -> says_bare
    | _holding nps                           -> holds
_keeping: "keeping" | "leaving" | "with"
_holding: "holding" | "still" "holding" | "keeping" "hold" "of" | "gripping" | "carrying"

"""
GRAMMAR = SENTENCES + INSTRUCTIONS + NOUN_PHRASES

MAX_PARSES = 64  # a sentence with more readings than this is refused as too tangled to read
MAX_WORDS = 60  # and one longer than this, before its parses are counted (they grow fast)


# ---------------------------------------------------------------------------- the parser
@functools.cache
def _built() -> tuple[Lark, frozenset[str]]:
    return earley.build(GRAMMAR)


def parser() -> Lark:
    """The grammar built once (Earley: natural sentences are ambiguous, and every parse is
    kept so that the scene can tell which is meant)."""
    return _built()[0]


@functools.cache
def known_words() -> frozenset[str]:
    """Every word the grammar reads, and "please" (read past wherever it stands); the words of
    the closing courtesies (`typed.CODAS`) are read past only where they close a sentence."""
    return _built()[1] | {"please"}


def read(text: str) -> list[tuple[Item, ...]]:
    """Every parse of `text`, as items in the order said; `Unread` if it has none. A misspelt
    word is read as the known word a slip away with which the sentence reads, where exactly one
    spelling of the sentence does."""
    said_as = words(text)
    known = known_words()
    spelt = (typed.spellings(w, known) for w in said_as)
    respelt = [list(t) for t in itertools.islice(itertools.product(*spelt), typed.MAX_RESPELLINGS + 1)]
    if respelt != [said_as] and len(respelt) <= typed.MAX_RESPELLINGS:
        read_as = []
        for said in respelt:
            try:
                read_as.append(_readings(typed.minded(said, known)))
            except Unread:
                pass
        if len(read_as) == 1:
            return read_as[0]
    # what cannot be read is told in the words as typed, not as guessed
    return _readings(typed.minded(said_as, known))


def _readings(said: list[str]) -> list[tuple[Item, ...]]:
    said = typed.closed(said)
    if not said:
        raise Unread("the goal sentence is empty", said, None)
    known = known_words()
    for i, w in enumerate(said):
        if w not in known:
            raise Unread(f"unknown word {w!r}", said, i)
    if len(said) > MAX_WORDS:
        raise Unread(f"it has {len(said)} words, more than {MAX_WORDS}", said, None)
    joined = " ".join(said)
    try:
        tree = parser().parse(joined)
    except UnexpectedEOF:
        raise Unread("it ends too early", said, None) from None
    except UnexpectedToken as e:
        raise Unread(f"{e.token.value!r} does not fit there", said, e.token.column) from None
    except UnexpectedInput as e:
        raise Unread("it does not read as a goal", said, getattr(e, "column", None)) from None
    trees = CollapseAmbiguities().transform(tree)
    if len(trees) > MAX_PARSES:
        raise Unread(f"it reads {len(trees)} ways", said, None)
    build = Build(joined)
    readings: list[tuple[Item, ...]] = []
    refused = None
    for t in trees:
        try:
            items = build.transform(t)
        except VisitError as e:  # a reading whose meaning refuses itself
            if not isinstance(e.orig_exc, Unread):
                raise
            refused = e.orig_exc
            continue
        if items not in readings:
            readings.append(items)
    if not readings and refused is not None:
        raise Unread(refused.reason, said, None)
    return readings
