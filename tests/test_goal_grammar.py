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
