"""The goal grammar's words and parser: a sentence as whole words, parsed by lark's Earley.

A sentence is normalised (`words`) and parsed word by word (`Words`: each word one token),
every parse kept so that the scene can tell which is meant. Earley predicts every alternative
of each rule it expects; the grammar's long word lists (50 verbs that put something somewhere,
30 order and colour words) would be that many items at every place one may start, so
`classed` makes the alternatives of a rule that differ only in their first word one: that word
a class, matched by membership (`build`). A parse then takes about half the time, and the
grammar stays written as words."""

from __future__ import annotations

import re

from lark import Lark, Token
from lark.lexer import Lexer

_CONTRACTIONS = (
    (r"\bcan't\b", "can not"),
    (r"\bcannot\b", "can not"),
    (r"\bwon't\b", "will not"),
    (r"\bshan't\b", "shall not"),
    (r"n't\b", " not"),
    (r"\b(it|that|there|what|which|who)'s\b", r"\1 is"),
    (r"'re\b", " are"),
    (r"'d\b", " would"),
    (r"'ll\b", " will"),
    (r"'s\b", " 's"),
    (r"\b1st\b", "first"),
    (r"\b2nd\b", "second"),
    (r"\b3rd\b", "third"),
    (r"\b2\b", "two"),
    (r"\b3\b", "three"),
)


# Chat spellings, spelt out as contractions are (a slip of the keys is `typed.spellings`').
_SPELT = {
    "u": "you",
    "pls": "please",
    "plz": "please",
    "thx": "thanks",
    "ur": "your",
    "r": "are",
    "thats": "that is",
    "dont": "do not",
    "doesnt": "does not",
    "isnt": "is not",
    "cant": "can not",
    "wont": "will not",
    "shouldnt": "should not",
    "im": "i am",
    "lets": "let 's",
    "whats": "what is",
    "n": "and",
}


def words(text: str) -> list[str]:
    """The sentence as the grammar's words: lower case, contractions spelt out ("isn't": "is
    not", "block's": "block 's"), hyphens as spaces, commas and colons kept as words of their own
    (they join items and lists; what follows a colon says what was named before it),
    semicolons read as commas, the rest of the punctuation dropped."""
    t = text.lower().replace("\u2019", "'").replace("\u2018", "'")
    for pattern, spelt in _CONTRACTIONS:
        t = re.sub(pattern, spelt, t)
    t = re.sub(r"(\d)\s*(°|º|deg\b)", r"\1 degrees", t)
    t = t.replace("&", " and ")
    t = re.sub("--+|\u2014|\u2013", ",", t)
    t = t.replace(";", ",")
    t = re.sub(r"[-/]", " ", t)
    t = re.sub(r"[.!?\"()]", " ", t)
    t = t.replace(",", " , ").replace(":", " : ")
    return [s for w in t.split() for s in _SPELT.get(w, w).split()]


def spoken(said: list[str]) -> str:
    """Normalised words written back as a person writes them: "block , then" as "block,
    then", "block 's" as "block's"."""
    return " ".join(said).replace(" ,", ",").replace(" :", ":").replace(" 's", "'s")


_RULE = re.compile(r"^([!?]?_?[a-z]\w*)\s*:(.*)$")
_LEADING_WORD = re.compile(r'^\s*"([^"\s]+)"\s*(.*?)\s*$')


def alternatives(body: str) -> list[str]:
    """A rule's body split at its top-level "|" (not inside brackets or quotes)."""
    alts, depth, quoted, current = [], 0, False, ""
    for ch in body:
        quoted = quoted != (ch == '"')
        if not quoted and ch in "([":
            depth += 1
        elif not quoted and ch in ")]":
            depth -= 1
        elif not quoted and ch == "|" and depth == 0:
            alts.append(current)
            current = ""
            continue
        current += ch
    return [*alts, current]


def definitions(grammar: str) -> list[list[str]]:
    """The grammar's lines, grouped by the rule each defines (a line of its own otherwise)."""
    out: list[list[str]] = []
    for line in grammar.split("\n"):
        if _RULE.match(line) or not out or not line.startswith(" ") or not line.strip():
            out.append([line])
        else:
            out[-1].append(line)
    return out


def first_words(grammar: str, rules: tuple[str, ...]) -> frozenset[str]:
    """The first word of each alternative of `rules` that starts with a word."""
    found: set[str] = set()
    for lines in definitions(grammar):
        m = _RULE.match(lines[0])
        if m is not None and m.group(1) in rules:
            for a in alternatives(" ".join([m.group(2), *lines[1:]])):
                w = re.match(r'^\s*"([^"\s]+)"', a)
                found |= {w.group(1)} if w else set()
    return frozenset(found)


def classed(grammar: str) -> tuple[str, dict[str, frozenset[str]]]:
    """The grammar with each rule's alternatives that differ only in their first word (three
    one-word alternatives or more, or two longer ones) made one, that word a class of its own,
    and the words of each class."""
    out: list[str] = []
    classes: dict[str, frozenset[str]] = {}
    for lines in definitions(grammar):
        m = _RULE.match(lines[0])
        if m is None:
            out += lines
            continue
        alts = alternatives(re.sub(r"//[^\n]*", "", " ".join([m.group(2), *lines[1:]])))
        tails: dict[str, list[str]] = {}
        for a in alts:
            w = _LEADING_WORD.match(a)
            if w is not None:
                tails.setdefault(w.group(2), []).append(w.group(1))
        kept: list[str] = []
        for a in alts:
            w = _LEADING_WORD.match(a)
            words = tails.get(w.group(2), []) if w is not None else []
            if w is None or len(words) < (3 if not w.group(2) else 2):
                kept.append(a.strip())
            elif words[0] == w.group(1):
                # an underscore: the class's token is left out of the tree, as a quoted word's is
                name = f"_W_{m.group(1).strip('!?_').upper()}_{len(classes)}"
                classes[name] = frozenset(words)
                kept.append(f"{name} {w.group(2)}".strip())
                out.append(f"{name}: " + " | ".join(f'"{x}"' for x in dict.fromkeys(words)))
        out.append(f"{m.group(1)}: {' | '.join(kept)}")
    return "\n".join(out), classes


class Words(Lexer):
    """Each word of a normalised sentence is one token: of the terminal that spells it, or of
    none where only word classes hold it (the parser's matcher, `build`, matches those)."""

    def __init__(self, lexer_conf) -> None:
        self.types = {t.pattern.value: t.name for t in lexer_conf.terminals if t.pattern.type == "str"}

    def lex(self, data: str):
        pos = 0
        for i, word in enumerate(data.split(" ")):
            # The column is the word's index: where a parse fails is named as a word.
            kind = self.types.get(word, "WORD")
            yield Token(kind, word, start_pos=pos, end_pos=pos + len(word), line=1, column=i)
            pos += len(word) + 1


def build(grammar: str) -> tuple[Lark, frozenset[str]]:
    """The Earley parser of `grammar` (every parse kept), and every word it reads."""
    text, classes = classed(grammar)
    member: dict[str, set[str]] = {}
    for name, ws in classes.items():
        for w in ws:
            member.setdefault(w, set()).add(name)

    def matches(term, token) -> bool:
        return term.name == token.type or term.name in member.get(token.value, ())

    lark = Lark(text, parser="earley", lexer=Words, ambiguity="explicit", propagate_positions=True)
    earley = lark.parser.parser
    # lark's Earley matches a terminal to a token by its name; a class matches by membership
    assert hasattr(earley, "term_matcher"), "lark's Earley parser changed: see words/earley.py"
    earley.term_matcher = matches
    spelt = {t.pattern.value for t in lark.lexer_conf.terminals if t.pattern.type == "str"}
    return lark, frozenset(spelt.union(*classes.values()))
