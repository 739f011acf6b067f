"""The nearest reading of a sentence that cannot be read: what a refusal offers instead.

Tried in order, the first that reads wins: the failed word replaced by the known words that
look most like it (or dropped); the phrase that named nothing replaced by the name of each
object of the scene; and last, of a few plain sentences about the scene's objects (a state
and an instruction per relation), the one nearest to what was said, word for word.
"""

from __future__ import annotations

import difflib
import functools
from collections.abc import Callable

from afford.words import earley, grammar
from afford.words.facts import RELATIONS, State
from afford.words.reference import names

TRIES = 4  # sentences tried against the scene before falling back to the plain ones (each a parse)
# and at most this many words parsed in all, the sentence's own included: a parse takes about
# 2 ms a word, and a refusal must stay under 50 ms with the plain sentence it may fall back to
WORDS_TRIED = 20
# Plain sentences per relation: {x} the subject, {y} the other object; a state, an instruction.
PLAIN = {
    "on": ("{x} is on {y}", "put {x} on {y}"),
    "on_table": ("{x} is on the table", "put {x} on the table"),
    "gone": ("{x} is gone", "push {x} off the table"),
    "tipped": ("{x} has tipped over", "knock {x} over"),
    "upright": ("{x} is upright", "stand {x} up"),
    "held": ("the gripper holds {x}", "pick up {x}"),
    "lies": ("{x} lies across", "turn {x} lengthwise"),
    "left_of": ("{x} is left of {y}", "move {x} left of {y}"),
    "right_of": ("{x} is right of {y}",),
    "in_front_of": ("{x} is in front of {y}",),
    "behind": ("{x} is behind {y}",),
}


# The rules whose words make a goal a sentence rather than a phrase (a suggestion holds one).
VERB_RULES = (
    "_holds", "_be", "_have", "_be_base", "_verb", "_verb_base", "_stand", "_modal", "_do", "_keep",
    "_putdown", "_make", "_turn", "_swap", "_hide", "_put", "_stand_verb", "_take", "_give", "_tip",
    "_topple", "_rid", "_keep_holding", "_let_go",
)  # fmt: skip


@functools.cache
def verbs() -> frozenset[str]:
    """The verbs and auxiliaries that start VERB_RULES' alternatives, and "pick" ("pick up")."""
    return (earley.first_words(grammar.GRAMMAR, VERB_RULES) | {"pick"}) - {"both", "all"}


def plain_sentences(state: State) -> list[str]:
    """Sentences about the scene's named objects in plain words, every one readable."""
    called = {k: v[0] for k, v in names(state).items()}
    out = []
    for key, forms in PLAIN.items():
        relation = RELATIONS["on" if key == "on_table" else key]
        for k, x in called.items():
            if state.kind(k) not in relation.subjects:
                continue
            ys = [y for o, y in called.items() if o != k and state.kind(o) in relation.other_kinds]
            for form in forms:
                out += [form.format(x=x, y=y) for y in ys] if "{y}" in form else [form.format(x=x)]
    return out


def nearest(
    said: list[str],
    state: State,
    reads: Callable[[str], bool],
    at: int | None = None,
    phrase: str = "",
    fits: tuple[str, ...] = (),
) -> str:
    """The reading nearest to `said` (the sentence's words) that `reads` accepts: `at` the
    index of the word that failed, `phrase` the words of a noun phrase that named nothing,
    `fits` the kinds that would fit in its place (their names are tried first)."""
    text = " ".join(said)
    tries: list[str] = []
    known = sorted(grammar.known_words())
    unknown = [i for i, w in enumerate(said) if w not in grammar.known_words()]
    if unknown:
        fixed = [(difflib.get_close_matches(w, known, n=1, cutoff=0.6) or [""])[0] for w in said]
        tries.append(
            " ".join(f if i in unknown else w for i, (w, f) in enumerate(zip(said, fixed, strict=True)))
        )
    if at is not None and at < len(said):
        # an unknown word's nearest spelling is tried above already
        n = 1 if at in unknown else 2
        for w in difflib.get_close_matches(said[at], known, n=n, cutoff=0.6):
            tries.append(" ".join([*said[:at], w, *said[at + 1 :]]))
        tries.append(" ".join(said[:at] + said[at + 1 :]))
    if phrase and phrase in text:
        alike = difflib.SequenceMatcher(None, phrase)
        named = sorted(
            {
                (state.kind(k) not in fits, v[0])
                for k, v in names(state).items()
                if not fits or state.kind(k) in fits
            },
            key=lambda fit_name: (fit_name[0], -_spelt_alike(alike, fit_name[1]), fit_name[1]),
        )
        # one object in the place of several ("both cups are ..."): the verb agrees with it
        tries += [text.replace(phrase, n, 1).replace(f"{n} are ", f"{n} is ") for _, n in named]
    # a suggestion is a sentence: a verbless phrase reads ("cup on the support", "the ball gone
    # on the block"), but it is not what one offers a person to write
    verb_words = verbs()
    budget = WORDS_TRIED - len(said)
    for t in list(dict.fromkeys(" ".join(t.split()) for t in tries))[:TRIES]:
        if not t or t == text or not any(w in verb_words for w in t.split()):
            continue
        budget -= len(t.split())
        if budget < 0:
            break
        if reads(t):
            return earley.spoken(t.split())
    plain = plain_sentences(state)
    plain.sort(key=lambda p: -likeness(p, text))
    return next((p for p in plain[:3] if reads(p)), plain[0] if plain else "the cup is on the table")


def likeness(a: str, b: str) -> float:
    """How alike two sentences are, word for word (0 to 1)."""
    return difflib.SequenceMatcher(None, a.split(), b.split()).ratio()


def _spelt_alike(matcher: difflib.SequenceMatcher, name: str) -> float:
    """How alike a name is spelt to the phrase `matcher` was given, letter for letter."""
    matcher.set_seq1(name)
    return matcher.ratio()
