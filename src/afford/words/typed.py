"""What is typed, made into the words the goal grammar reads: a word one slip of the keys from
a known word (`spellings`), courtesies that ask for nothing read past (`closed`), "would you
mind VERBing" as "please VERB" (`minded`). `grammar.read` parses what these give.
"""

from __future__ import annotations

# Courtesies that close a request, read past before parsing ("..., would you?", "thanks so
# much", "that would be lovely"): in the grammar they cost a third of every parse's time.
_MUCH = ("", "so much", "very much", "a lot", "in advance")
_NICE = (
    "lovely wonderful great nice perfect fantastic amazing helpful brilliant ideal good awesome appreciated"
)
CODAS = sorted(  # the longest first, as `closed` tries them
    (tuple(c.split())
    for c in (
        *(f"thanks {m}" for m in _MUCH),
        *(f"thank you {m}" for m in _MUCH),
        *(f"that would be {n}" for n in _NICE.split()),
        *(f"{m} you" for m in ("would", "could", "will", "can")),
        "pretty please", "if you would", "if you could", "if you do not mind", "nothing else", "cheers",
        "instead", "if that is not too much trouble", "if it is not too much trouble",
    )),
    key=len,
    reverse=True,
)  # fmt: skip


def closed(said: list[str]) -> list[str]:
    """The words without the courtesies that close them (`CODAS`), however many, and without
    "please" wherever it stands: it asks for nothing ("the block across please, and ...")."""
    said = _unpleased(said)
    for coda in CODAS:
        n = len(coda)
        if len(said) > n and tuple(said[-n:]) == coda:
            return closed(said[: -n - (said[-n - 1] == ",")])
    return said


def _unpleased(said: list[str]) -> list[str]:
    said = said[2:] if said[:2] == ["please", ","] else said  # "please, put ...": no comma opens it
    out: list[str] = []
    for i, w in enumerate(said):
        if w == "pretty" and said[i + 1 : i + 2] == ["please"]:
            continue
        if w != "please":
            out.append(w)
        elif out and out[-1] == "," and (i + 1 == len(said) or said[i + 1] in (",", "and")):
            out.pop()  # "X, please, and Y": one comma stays
    return out


def minded(said: list[str], known: frozenset[str]) -> list[str]:
    """A request read as "please ...": "would you mind rotating the block" as "please rotate the
    block", the verb after "mind" in its base form where that is a word the grammar reads."""
    for i in range(len(said) - 3):
        if said[i] in ("would", "do", "will") and said[i + 1 : i + 3] == ["you", "mind"]:
            base = _base(said[i + 3], known)
            if base is not None:
                return [*said[:i], "please", base, *minded(_and_based(said[i + 4 :], known), known)]
    return said


def _and_based(said: list[str], known: frozenset[str]) -> list[str]:
    """After "would you mind VERBing", each "and VERBing" in its base form too."""
    return [(w if i == 0 or said[i - 1] != "and" else _base(w, known) or w) for i, w in enumerate(said)]


def _base(verb: str, known: frozenset[str]) -> str | None:
    """The base form of a VERBing ("rotating": "rotate", "putting": "put") that the grammar
    reads, or None."""
    if not verb.endswith("ing"):
        return None
    stem = verb[:-3]
    bases = (stem, stem + "e", stem[:-1] if stem[-2:-1] == stem[-1:] else "")
    return next((b for b in bases if b in known), None)


_LETTERS = "abcdefghijklmnopqrstuvwxyz"


def _one_slip(word: str) -> set[str]:
    """Every string one slip of the keyboard from `word`: a letter dropped, added or changed,
    or two neighbours swapped."""
    cut = [(word[:i], word[i:]) for i in range(len(word) + 1)]
    return {
        *(a + b[1:] for a, b in cut if b),
        *(a + b[1] + b[0] + b[2:] for a, b in cut if len(b) > 1),
        *(a + c + b[1:] for a, b in cut if b for c in _LETTERS),
        *(a + c + b for a, b in cut for c in _LETTERS),
    }


def spellings(word: str, known: frozenset[str]) -> list[str]:
    """`word` as the grammar may know it: itself, or the known words a slip away (none guessed
    for words of fewer than three letters)."""
    if word in known or len(word) < 3 or not word.isalpha():
        return [word]
    return sorted(_one_slip(word) & known) or [word]


MAX_RESPELLINGS = 4  # sentences tried with the misspelt words' candidates (each a parse)
