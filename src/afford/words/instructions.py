"""The goal grammar's instructions ("put the red ball on the block", "knock the cup over", "hand
me the ball"): each asks for the state its rule's name gives (`parses.Build`). `grammar.py`
joins these rules to those of goals and states, `nouns.py` gives the noun phrases.
"""

INSTRUCTIONS = r"""
// ------------------------------------------------------------------ instructions
command: _polite* action _tail?                        -> do
       | _polite* _keep nps "from" ving _tail?         -> keep_from
       | _polite* _dont action _tail?                  -> dont
       | _polite* action ","? "without" ing _tail?     -> without
_polite: _courtesy ","?
_courtesy: "is" "it" "possible" "to" | "can" "you" | "could" "you" | "would" "you" | "will" "you"
         | "i" "want" "you" "to"
         | "i" "need" "you" "to" | "i" "would" "like" "you" "to" | "robot" | "now" | "go" "ahead" "and"
         | "try" "to" | "kindly" | "you" "should" | "you" "must" | "go" "and" | "first" | "finally" | "just"
         | "ok" | "okay" | "hey" | "lastly" | "next" | "also" | "would" "you" "be" "so" "kind" "as" "to"
         | "be" "so" "kind" "as" "to" | "would" "you" "kindly" | "could" "you" "kindly"
         | "i" "would" "love" "you" "to"
         | "do" "me" "a" "favour" "and" | "do" "me" "a" "favor" "and" | "hmm" | "um" | "well"
_tail: "for" "me" | "thanks" | "thank" "you" | "now" | "," "thanks"
     | "right" "now" | "if" "you" "can" | _too | "also" | "," _too
_dont: "do" "not" | "never" | "be" "careful" "not" "to" | "take" "care" "not" "to"
action: _put nps complements                  -> put
      | _put _particle nps complements        -> put
      | _putdown nps "down"                   -> put_down
      | _putdown "down" nps                   -> put_down
      | _make nps vstate                      -> put
      | _turn nps angle? _direction?          -> turn
      | _swap nps ("round" | "around" | "over")?  -> swap
      | _swap nps "with" nps                  -> swap
      | _swap "the" ("places" | "positions" | "spots") "of" nps -> swap
      | _hide nps (_hide_at nps)?             -> rid
      | _stand_verb nps complements           -> put_standing
      | _stand_verb nps "up"                  -> stand_up
      | _stand_verb "up" nps                  -> stand_up
      | "pick" "up" nps                       -> take
      | "pick" nps "up"                       -> take
      | "pick" nps                            -> take
      | "keep" nps "up"                       -> stand_up
      | _take nps                             -> take
      | _give "me" nps                        -> take
      | _give nps "a" degrees? _a_turn        -> turn
      | _perform "a" degrees? _a_turn "with" nps -> turn_with
      | _clear "off"? nps                     -> clear
      | _clear nps "off"                      -> clear
      | _give nps "to" "me"                   -> take
      | _tip "over" nps                       -> tip
      | _tip nps "over"                       -> tip
      | _topple nps                           -> tip
      | _rid nps                              -> rid
      | _rid nps _hide_at nps                 -> rid
      | "throw" "away" nps                    -> rid
      | _keep_holding nps                     -> hold
      | _let_go nps                           -> release
ing: _tip_ing "over" nps                      -> tip
   | _tip_ing nps "over"                      -> tip
   | _toppling_ing nps                        -> tip
   | _push_ing nps _off table                 -> rid
   | _push_ing nps _off nps                   -> ing_off
   | "dropping" nps                           -> rid
_toppling_ing: "toppling" | "tipping" | "upsetting" | "overturning" | "knocking" "over" | "knocking" "down"
_direction: "clockwise" | "counterclockwise" | "anticlockwise" | "counter" "clockwise" | "anti" "clockwise"
          | "to" "the" ("left" | "right")
_a_turn: "turn" | "twist" | "spin" | "rotation"
_perform: "make" | "do" | "perform" | "execute"
_clear: "clear" | "empty" | "unload" | "free" "up"
_putdown: "put" | "set" | "lay" | "place"
_make: "make" | "let" | "have" | "get"
_turn: "turn" | "rotate" | "spin" | "twist" | "swivel" | "pivot" | "reorient"
_swap: "swap" | "switch" | "exchange" | "trade" | "interchange"
_hide: "hide" | "conceal" | "tuck"
_hide_at: _under | "behind"
_put: "put" | "place" | "set" | "move" | "stack" | "lay" | "drop" | "bring" | "carry" | "slide" | "push"
    | "balance" | "transfer" | "shift" | "relocate" | "return" | "deposit" | "park" | "plop" | "plonk"
    | "raise" | "send" | "bump" | "tap" | "poke" | "hit" | "dump" | "perch" | "settle" | "let" | "center"
    | "centre" | "arrange" | "line" | "stick" | "land" | "clear"
    | "hold" | "chuck" | "straighten" | "align" | "square" | "shove" | "roll" | "throw" | "toss"
    | "sweep" | "knock" | "turn" | "rotate" | "get" | "have" | "keep"
    | "leave" | "make" | "lift" | "take" | "remove" | "kick" | "nudge" | "position" | "sit" | "rest"
    | "pop" | "spin" | "swing" | "flick" | "tip" | "lower" | "pull" | "drag"
_stand_verb: "stand"
_keep_holding: "keep" "holding" | "keep" "hold" "of" | "keep" "a" "hold" "of" | "keep" "gripping"
             | "keep" "carrying" | "continue" "holding" | "continue" "to" "hold" | "carry" "on" "holding"
             | "hang" "on" "to" | "go" "on" "holding" | "stay" "holding"
_let_go: "let" "go" "of" | "release" | "drop"
_take: "grab" | "grasp" | "hold" | "take" | "lift" | "fetch" | "get" | "collect" | "grip" | "lift" "up"
     | "hold" "on" "to" | "hold" "onto" | "seize" | "catch" | "snatch" | "take" "hold" "of"
     | "grab" "hold" "of" | "hold" "up"
     | "raise" "up" | "pick" "out"
_give: "hand" | "give" | "bring" | "pass" | "fetch"
_tip: "knock" | "tip" | "push" | "turn" | "flip" | "topple" | "tilt"
_topple: "topple" | "upset" | "overturn" | "tilt" | "tip"
_rid: "chuck" | "ditch" | "bin" | "remove" | "get" "rid" "of" | "dispose" "of" | "discard"
    | "clear" "away" | "eliminate"
_tip_ing: "knocking" | "tipping" | "pushing" | "turning"
_push_ing: "knocking" | "pushing" | "throwing" | "sweeping" | "rolling" | "moving"

"""
