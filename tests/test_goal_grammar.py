"""Goals said as people say them (tests/goal_sentences.json, written by hand, not by the
sampler): each reads to the clauses it means in its scene, and what cannot be read is refused
in one line that names what failed and offers a reading that can."""

import json
from pathlib import Path

import numpy as np
import pytest

from afford.sim.specs import specs_from_json
from afford.words.clauses import Clause
from afford.words.facts import State
from afford.words.sentences import SentenceError, parse, read_clause, sample_statement, tokens, vocabulary

ROOT = Path(__file__).resolve().parents[1]
DATA = json.loads((Path(__file__).parent / "goal_sentences.json").read_text())
SHARE = 0.95  # of the sentences that must read to the clauses they mean


def scene_state(name: str) -> State:
    return State.of_specs(specs_from_json(DATA["scenes"][name]))


def shown(clause: Clause, state: State) -> str:
    """A clause as the data file writes it: '[not] relation subject [other]'."""
    f = clause.fact
    other = state.slots[f.other] if isinstance(f.other, int) else f.other
    return " ".join(
        w for w in ("not" if clause.negated else "", f.relation, state.slots[f.subject], other) if w
    )


def test_the_hand_written_sentences_read_to_the_clauses_they_mean():
    assert len(DATA["read"]) >= 60
    wrong = []
    for case in DATA["read"]:
        state = scene_state(case["scene"])
        try:
            got = [shown(c, state) for c in parse(case["text"], state).clauses]
        except SentenceError as e:
            got = [f"refused: {e}"]
        if got != case["clauses"]:
            wrong.append(f"{case['text']!r}: {got} (meant {case['clauses']})")
    share = 1 - len(wrong) / len(DATA["read"])
    assert share >= SHARE, "\n".join(wrong)
    assert not wrong, "\n".join(wrong)


# Sentences written cold, by people who never saw the grammar, for the scenes above: the
# development sets (the grammar was fixed against them: the first set, then the first held-out
# set once measured, then the second held-out set, measured once at 44dd5df: 80 of 89).
COLD = json.loads((Path(__file__).parent / "goal_sentences_cold.json").read_text())
HELDOUT = json.loads((Path(__file__).parent / "goal_sentences_heldout.json").read_text())
HELDOUT_FLOOR = 0.99  # of the held-out set read rightly or refused where meant: 100 of 101
HELDOUT2 = json.loads((Path(__file__).parent / "goal_sentences_heldout2.json").read_text())
HELDOUT2_FLOOR = 0.97  # 87 of 89 with the rules for its failure kinds
# The third held-out set, measured once at 3b16099: 72 of 82; then development data.
HELDOUT3 = json.loads((Path(__file__).parent / "goal_sentences_heldout3.json").read_text())
HELDOUT3_FLOOR = 0.97  # 80 of 82 with the rules for its failure kinds
# Three writers' 120 sentences each, in voices of their own (terse, chatty, varied): development data.
WRITERS = json.loads((Path(__file__).parent / "goal_sentences_writers.json").read_text())
WRITERS_FLOOR = 0.93  # 336 of 360; before any rule for them, 182 of 360
# The fourth held-out set, measured once at db081a6: 84 of 90; then development data.
HELDOUT4 = json.loads((Path(__file__).parent / "goal_sentences_heldout4.json").read_text())
HELDOUT4_FLOOR = 0.98  # 89 of 90
# The fifth held-out set, 120 sentences, measured once at 1e9cbf1: 107 of 120; then development data.
HELDOUT5 = json.loads((Path(__file__).parent / "goal_sentences_heldout5.json").read_text())
HELDOUT5_FLOOR = 0.98  # 118 of 120
# The sixth held-out set, 120 sentences, measured once at 84e8047: 101 of 120, the honest figure.
HELDOUT6 = json.loads((Path(__file__).parent / "goal_sentences_heldout6.json").read_text())
HELDOUT6_FLOOR = 0.84


def as_goal(clauses: list[str]) -> list[str]:
    """Clauses as the goal they ask for: sorted, and "not on X Y" left out where X is also put
    on something else or gone, which it implies ("take the cup off the block and put it on the
    table"): writers differ in whether they say it."""
    placed = {c.split()[1] for c in clauses if c.split()[0] in ("on", "on_end", "gone")}
    return sorted(c for c in clauses if not (c.startswith("not on ") and c.split()[2] in placed))


def measured(sentences: dict) -> tuple[float, list[str]]:
    """The share of a cold set read to the clauses meant (as a goal, `as_goal`) or refused where
    meant, and what went wrong with the rest."""
    wrong = []
    for kind in ("read", "refuse"):
        for case in sentences[kind]:
            state = scene_state(case["scene"])
            try:
                got = as_goal([shown(c, state) for c in parse(case["text"], state).clauses])
            except SentenceError as e:
                got = [f"refused: {e}"]
            meant = as_goal(case["clauses"]) if kind == "read" else None
            if (got != meant) if kind == "read" else not got[0].startswith("refused"):
                wrong.append(f"{case['scene']}: {case['text']!r}: {got} (meant {meant or 'a refusal'})")
    return 1 - len(wrong) / (len(sentences["read"]) + len(sentences["refuse"])), wrong


def test_the_sentences_written_cold_read_as_meant():
    assert len(COLD["read"]) + len(COLD["refuse"]) >= 100
    share, wrong = measured(COLD)
    assert not wrong, "\n".join(wrong)


def test_the_held_out_sentences_read_as_meant():
    assert len(HELDOUT["read"]) + len(HELDOUT["refuse"]) >= 60
    share, wrong = measured(HELDOUT)
    assert share >= HELDOUT_FLOOR, f"{share:.3f}\n" + "\n".join(wrong)


def test_the_second_held_out_sentences_read_as_measured():
    assert len(HELDOUT2["read"]) + len(HELDOUT2["refuse"]) >= 60
    share, wrong = measured(HELDOUT2)
    assert share >= HELDOUT2_FLOOR, f"{share:.3f}\n" + "\n".join(wrong)


@pytest.mark.parametrize(
    ("sentences", "floor", "at_least"),
    [
        (HELDOUT3, HELDOUT3_FLOOR, 82),
        (WRITERS, WRITERS_FLOOR, 360),
        (HELDOUT4, HELDOUT4_FLOOR, 90),
        (HELDOUT5, HELDOUT5_FLOOR, 120),
        (HELDOUT6, HELDOUT6_FLOOR, 120),
    ],
    ids=["heldout3", "writers", "heldout4", "heldout5", "heldout6"],
)
def test_more_sentences_written_cold_read_as_measured(sentences, floor, at_least):
    assert len(sentences["read"]) + len(sentences["refuse"]) >= at_least
    share, wrong = measured(sentences)
    assert share >= floor, f"{share:.3f}\n" + "\n".join(wrong)


COLD_SETS = {
    "cold": (COLD, 1.0),
    "heldout": (HELDOUT, HELDOUT_FLOOR),
    "heldout2": (HELDOUT2, HELDOUT2_FLOOR),
    "heldout3": (HELDOUT3, HELDOUT3_FLOOR),
    "writers": (WRITERS, WRITERS_FLOOR),
    "heldout4": (HELDOUT4, HELDOUT4_FLOOR),
    "heldout5": (HELDOUT5, HELDOUT5_FLOOR),
    "heldout6": (HELDOUT6, HELDOUT6_FLOOR),
}


@pytest.mark.parametrize(("sentences", "floor"), list(COLD_SETS.values()), ids=list(COLD_SETS))
def test_every_refusal_is_one_line_with_a_sentence_that_reads(sentences, floor):
    """Each refusal of a cold set, meant or not, offers a reading a person would write: a
    sentence (it has a verb, as every goal the grammar reads as a sentence does), written as
    people write (no space before a comma), read in the same scene."""
    from afford.words.suggest import verbs

    refused = 0
    for case in sentences["read"] + sentences["refuse"]:
        state = scene_state(case["scene"])
        try:
            parse(case["text"], state)
            continue
        except SentenceError as e:
            message = str(e)
        refused += 1
        assert "\n" not in message
        suggested = message.split("; did you mean ")[-1]
        assert suggested.startswith("'") and suggested.endswith("'?"), message
        suggested = suggested[1:-2]
        parse(suggested, state)
        assert any(w in verbs() for w in suggested.split()) and " ," not in suggested, message
        assert "suggests" not in case or suggested == case["suggests"], message
    every = len(sentences["read"]) + len(sentences["refuse"])
    assert refused >= len(sentences["refuse"]) - int((1 - floor) * every)  # the misses its floor allows


def test_how_a_goal_was_read_is_written_back_in_words():
    """`afford plan --goal` prints its reading before it plans: each clause in words."""
    from afford.cli.words import goal_reading, reading_line

    state = scene_state("two-cups")
    text = "first put the left cup on the block, then push the ball off the table"
    reading = goal_reading(text, parse(text, state), state)
    assert reading["clauses"] == ["the left cup is on the block", "the ball is gone"]
    assert reading["facts"] == ["on cup0 block0", "gone ball0"]
    assert reading_line(reading) == "goal read as: the left cup is on the block; the ball is gone"


@pytest.mark.parametrize(
    ("scene", "text", "clauses"),
    [
        # a sequence is the state after all of it: its clauses together, the order not kept
        (
            "two-cups",
            "first knock over the left cup, then put the right cup on the block",
            ["on cup1 block0", "tipped cup0"],
        ),
        (
            "two-cups",
            "first put the left cup on the block, then the right cup",
            ["on cup0 block0", "on cup1 block0"],
        ),
        # a turn is said of how the block lies at the start (across here)
        ("two-cups", "turn the block", ["lies block0 lengthwise"]),
        ("two-cups", "rotate the block 180 degrees", ["lies block0 across"]),
        ("two-cups", "turn the block a quarter turn", ["lies block0 lengthwise"]),
        # "off the table" and "no longer on the table" are gone, "not on the table" is not on it
        ("cup-ball-block", "get the cup off the table", ["gone cup0"]),
        ("cup-ball-block", "the cup should no longer be on the table", ["gone cup0"]),
        ("cup-ball-block", "the cup should not be on the table", ["not on cup0 table"]),
        ("cup-ball-block", "the cup should no longer be upright", ["not upright cup0"]),
        # a purpose is part of the goal
        ("cup-ball-block", "move the ball so that it is behind the cup", ["behind ball0 cup0"]),
        ("stacked", "swap the cup and the ball", ["on ball0 block0", "on cup0 support0"]),
        ("two-supports", "put the cup where the ball is", ["on cup0 support0"]),
        ("two-supports", "put the cup on the empty support", ["on cup0 support1"]),
        # whose: what rests on the owner or what it rests on, at the start
        ("two-supports", "put the ball back on its post", ["on ball0 support0"]),
        ("two-supports", "put the cup on the ball's post", ["on cup0 support0"]),
        ("stacked", "take the cup off its block", ["not on cup0 block0"]),
        # "too" adds nothing; a state beside an instruction is part of the goal
        (
            "cup-ball-block",
            "knock the cup over, and push the ball off the table too",
            ["gone ball0", "tipped cup0"],
        ),
        (
            "cup-ball-block",
            "knock the cup over while the ball stays on the table",
            ["on ball0 table", "tipped cup0"],
        ),
        (
            "cup-ball-block",
            "put the ball on the block, keeping the cup upright",
            ["on ball0 block0", "upright cup0"],
        ),
        ("cup-ball-block", "while holding the ball, knock over the cup", ["held ball0", "tipped cup0"]),
        ("cup-ball-block", "pick up the ball and don't let go of it", ["held ball0"]),
        ("cup-ball-block", "pick up the cup, then let go of it", ["not held cup0"]),
        # what follows a colon names what the pronouns before it name
        (
            "stacked",
            "swap them: the cup on the support and the ball on the block",
            ["on ball0 block0", "on cup0 support0"],
        ),
    ],
)
def test_goals_said_in_more_ways_read_by_the_rules_of_the_grammar(scene, text, clauses):
    state = scene_state(scene)
    assert sorted(shown(c, state) for c in parse(text, state).clauses) == sorted(clauses)


def test_a_pronoun_looks_forward_only_across_a_colon():
    state = scene_state("cup-ball-block")
    with pytest.raises(SentenceError, match="'it' refers to nothing said before it"):
        parse("knock it over and put the cup on the block", state)


def test_what_a_goal_reads_to_is_written_in_words_the_agreement_model_knows():
    """The statement's text is what the model scores: every word in its vocabulary, each
    clause in a taught phrasing, and read back to the same clauses."""
    known = set(vocabulary())
    for case in DATA["read"]:
        state = scene_state(case["scene"])
        statement = parse(case["text"], state)
        assert set(tokens(statement.text)) <= known, statement.text
        for part in statement.text.split(" and "):
            read_clause(part)
        assert parse(statement.text, state).clauses == statement.clauses


def test_what_cannot_be_read_is_refused_in_one_line_with_a_reading_that_can():
    assert len(DATA["refuse"]) >= 12
    for case in DATA["refuse"]:
        state = scene_state(case["scene"])
        with pytest.raises(SentenceError) as e:
            parse(case["text"], state)
        message = str(e.value)
        assert case["error"] in message, message
        assert "\n" not in message
        suggested = message.split("; did you mean ")[-1]
        assert suggested.startswith("'") and suggested.endswith("'?"), message
        parse(suggested[1:-2], state)  # the suggestion reads in the same scene


def test_the_grammar_reads_every_sampled_sentence_as_the_taught_reader_does():
    """The sampler's phrasings, read by the grammar rather than by the phrasings themselves,
    give the same clauses: the two readers agree where both read."""
    from afford.words.reference import understand

    rng = np.random.default_rng(1)
    checked = 0
    for name in DATA["scenes"]:
        state = scene_state(name)
        for k in range(30):
            statement = sample_statement(state, bool(k % 2), rng)
            if statement is None:
                continue
            assert understand(statement.text, state) == statement.clauses, statement.text
            checked += 1
    assert checked >= 100


def test_a_sentence_that_reads_two_ways_in_the_scene_is_refused_with_both(monkeypatch):
    """Where the scene cannot tell two parses apart, neither is guessed: the refusal writes
    both readings (here two made up, as the test set's sentences all read one way)."""
    from afford.words import sentences
    from afford.words.facts import Fact
    from afford.words.reference import Ambiguous

    state = scene_state("cup-ball-block")
    cup, ball, block = (state.slots.index(n) for n in ("cup0", "ball0", "block0"))
    readings = [(Clause(Fact("on", ball, block)),), (Clause(Fact("left_of", ball, cup)),)]

    def two_ways(text, s):
        raise Ambiguous(readings)

    monkeypatch.setattr(sentences, "understand", two_ways)
    with pytest.raises(SentenceError, match="reads 2 ways") as e:
        parse("put the ball on the block left of the cup", state)
    assert "'the ball is on the block' or 'the ball is left of the cup'" in str(e.value)


def test_the_instruction_tasks_ask_for_what_the_sentence_tasks_describe(scene):
    """tasks/words-instructions holds tasks/words with each goal said as an instruction: the
    same scene, success predicate and clauses (test_task_files loads every task file)."""
    from afford.planning.tasks import load_task

    said = sorted((ROOT / "tasks" / "words").glob("*.json"))
    ordered = sorted((ROOT / "tasks" / "words-instructions").glob("*.json"))
    assert [p.name for p in said] == [p.name for p in ordered] and len(said) >= 10
    for a, b in zip(said, ordered, strict=True):
        sentence, instruction = json.loads(a.read_text()), json.loads(b.read_text())
        assert {k: v for k, v in sentence.items() if k not in ("goal", "challenge")} == {
            k: v for k, v in instruction.items() if k not in ("goal", "challenge")
        }
        one, other = load_task(a, scene), load_task(b, scene)
        assert set(one.goal.statement.clauses) == set(other.goal.statement.clauses), b.name
        assert instruction["goal"]["text"] != sentence["goal"]["text"]
