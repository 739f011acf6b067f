"""Goal sentences (words/): facts read from true poses of scripted scenes, sentences written
and read back, and what cannot be read refused with the word or clause named."""

import dataclasses

import numpy as np
import pytest
from scenarios import BLOCK_TOP_ON_TABLE

from afford.sim.constants import CUP
from afford.sim.scene import ObjectSpec as O
from afford.words.facts import State
from afford.words.sentences import SentenceError, parse, sample_statement

SIDE_DOWN = (np.cos(np.pi / 4), 0.0, np.sin(np.pi / 4), 0.0)  # the axis turned 90 degrees about y


def truth(text: str, state: State) -> bool:
    return parse(text, state).holds(state)


def test_a_cup_on_the_blocks_left_end(scene):
    scene.reset([O.upright("block", 0, 0.30), O.upright("cup", -0.09, 0.30, z=BLOCK_TOP_ON_TABLE)])
    s = State.of_scene(scene)
    assert truth("the cup is on the block and the blue cup sits at the left end of the block", s)
    assert truth("the block lies across and the cup stands upright", s)
    assert not truth("the cup is on the table", s)
    assert not truth("the cup is on the right end of the block", s)
    assert truth("the cup is not on the table and the yellow block does not lie lengthwise", s)


def test_a_ball_off_the_table_is_gone(scene):
    scene.reset([O.upright("ball", 0.1, 0.25), O.upright("cup", -0.1, 0.25)])
    s = State.of_scene(scene)
    assert truth("the ball is still there and the ball is right of the cup", s)
    poses = s.poses.copy()
    poses[s.slots.index("ball0")] = np.nan  # as a dataset stores an object that left the table
    gone = State(poses, -1, s.slots, s.members)
    assert truth("the ball has fallen off the table", gone)
    assert not truth("the ball is on the table", gone)


def test_a_toppled_cup(scene):
    scene.reset([O("cup", (0.0, 0.25, CUP.radius), SIDE_DOWN)])
    s = State.of_scene(scene)
    assert truth("the cup has tipped over", s) and truth("the cup lies on its side", s)
    assert not truth("the cup is upright", s)


def test_several_of_a_kind_are_named_by_their_place_from_the_left(scene):
    scene.reset([O.upright("support", 0.1, 0.3), O.upright("support", -0.1, 0.3), O.upright("cup", 0.0, 0.2)])
    s = State.of_scene(scene)
    assert truth("the left support is left of the right support", s)
    assert truth("the cup is in front of the left black support", s)
    with pytest.raises(SentenceError, match="names no object"):
        parse("the support is upright", s)


def test_what_cannot_be_read_is_refused_naming_it(scene):
    scene.reset([O.upright("cup", 0.0, 0.25)])
    s = State.of_scene(scene)
    with pytest.raises(SentenceError, match="unknown word 'teapot'"):
        parse("the teapot is on the table", s)
    with pytest.raises(SentenceError, match="cannot read 'the cup the table'"):
        parse("the cup the table", s)
    with pytest.raises(SentenceError, match="names no object"):
        parse("the ball is gone", s)


def test_sampled_statements_are_as_true_as_asked_and_read_back(scene):
    scene.reset(
        [
            O.upright("block", 0, 0.30),
            O.upright("cup", 0.09, 0.30, z=BLOCK_TOP_ON_TABLE),
            O.upright("ball", -0.1, 0.2),
        ]
    )
    s = State.of_scene(scene)
    rng = np.random.default_rng(0)
    made = 0
    for k in range(40):
        want = bool(k % 2)
        statement = sample_statement(s, want, rng)
        if statement is None:
            continue
        made += 1
        assert statement.holds(s) == want
        assert parse(statement.text, s).clauses == statement.clauses
    assert made >= 30


@pytest.mark.parametrize("readout, geometry", [("pool", False), ("attend", False), ("attend", True)])
def test_the_agreement_net_scores_clauses_learns_and_refuses_unknown_words(readout, geometry):
    import torch

    from afford.words.config import PRESETS
    from afford.words.model import AgreementNet
    from afford.words.sentences import vocabulary

    torch.manual_seed(0)
    config = dataclasses.replace(
        PRESETS["tiny"], vocabulary=tuple(vocabulary()), readout=readout, geometry=geometry
    )
    net = AgreementNet(config)
    # Images that differ only in a bright patch on the left or the right; "the cup is left of
    # the ball" is made true for the first kind and false for the second, and its negation the
    # other way round, so the model must read both the image and the clause.
    images = torch.zeros((8, 4, 128, 128))
    images[::2, :, 50:70, 10:30] = 1.0
    images[1::2, :, 50:70, 98:118] = 1.0
    clauses = ["the cup is left of the ball", "the cup is left of the ball"] * 2
    clauses += ["the cup is not left of the ball", "the cup is not left of the ball"] * 2
    encoded = net.token_ids(clauses)
    truths = torch.tensor([1.0, 0.0] * 2 + [0.0, 1.0] * 2)
    assert net(images, encoded).shape == (8,)
    # At lr 1e-2 the geometric read made Adam bounce past the plateau (a loss of 1.9 at step 200
    # with 2 threads); at 3e-3 every readout is past it by step ~160 with 1 or 2 threads.
    opt = torch.optim.Adam(net.parameters(), lr=3e-3)
    losses = []
    for _ in range(250):
        loss = torch.nn.functional.binary_cross_entropy_with_logits(net(images, encoded), truths)
        opt.zero_grad()
        loss.backward()
        opt.step()
        losses.append(loss.item())
    assert max(losses[-20:]) < 0.5 * losses[0]
    both = net.statement_logprob(images[:2], "the cup is on the table and the ball is gone")
    assert both.shape == (2,) and bool((both <= 0).all())
    with pytest.raises(SentenceError, match="unknown word 'teapot'"):
        net.token_ids(["the teapot is gone"])


def test_a_sentence_goal_in_a_task_file_is_read_against_its_scene(tmp_path, scene):
    import json

    from afford.planning.tasks import TaskError, load_task

    task = {
        "name": "words",
        "scene": {
            "objects": [
                {"kind": "cup", "pos": [0.12, 0.2, 0.0425]},
                {"kind": "block", "pos": [0, 0.3, 0.025]},
            ]
        },
        "goal": {"text": "the cup is on the block"},
        "max_steps": 2,
        "success": {"on": {"object": "cup0", "host": "block0"}},
    }
    path = tmp_path / "t.json"
    path.write_text(json.dumps(task))
    loaded = load_task(path, scene)
    assert loaded.goal.text == "the cup is on the block" and not loaded.goal.negative
    task["goal"] = {"text": "the ball is on the block"}
    path.write_text(json.dumps(task))
    with pytest.raises(TaskError, match="goal.text: 'the ball' names no object"):
        load_task(path, scene)


def test_a_ball_under_the_blocks_overhang_is_gone_from_the_camera(scene):
    from scenarios import SUPPORT_TOP

    from afford.words.facts import hidden_in_image

    block_on_support = [O.upright("support", 0.01, 0.34), O.upright("block", 0.01, 0.34, 0.0, z=SUPPORT_TOP)]
    scene.reset([O.upright("ball", 0.09, 0.34), *block_on_support])
    s = State.of_scene(scene)  # the renderer's segmentation
    assert truth("the ball is gone", s) and not truth("the ball is on the table and the ball is not gone", s)
    assert hidden_in_image(s, scene.observe()) == s.hidden  # the colour test a dataset's images get
    scene.reset([O.upright("ball", 0.09, 0.25), *block_on_support])
    s = State.of_scene(scene)
    assert not truth("the ball is gone", s) and not hidden_in_image(s, scene.observe())


def test_clauses_at_the_vague_edge_of_their_words_are_not_sampled(scene):
    from afford.words.facts import Fact
    from afford.words.sentences import sample_clause

    scene.reset([O.upright("cup", -0.031, 0.3), O.upright("ball", 0.0, 0.2)])
    s = State.of_scene(scene)
    cup, ball = s.slots.index("cup0"), s.slots.index("ball0")
    assert Fact("left_of", cup, ball).holds(s) and not Fact("left_of", cup, ball).clear(s)
    assert Fact("behind", cup, ball).clear(s)  # 10 cm: clearly behind
    rng = np.random.default_rng(0)
    for _ in range(50):
        c = sample_clause(s, bool(rng.random() < 0.5), rng)
        assert c is None or c.fact.relation not in ("left_of", "right_of") or c.fact.clear(s)


def test_no_agreement_model_is_one_clear_error(tmp_path, monkeypatch):
    import afford.shipped
    from afford.planning.goal import GoalError
    from afford.planning.sentence_goal import load_agreement

    monkeypatch.setattr(afford.shipped, "WEIGHTS", tmp_path)
    with pytest.raises(GoalError, match="afford train goals"):
        load_agreement(tmp_path / "elsewhere")


def test_object_maps_mark_each_kind_where_the_camera_sees_it(scene):
    from afford.sim import camera
    from afford.sim.constants import KINDS
    from afford.words.data import object_maps

    scene.reset([O.upright("cup", -0.1, 0.25), O.upright("ball", 0.1, 0.25)])
    s = State.of_scene(scene)
    maps = object_maps(s, 16)
    assert maps.shape == (len(KINDS), 16, 16)
    for kind in ("cup", "ball"):
        k = s.slots.index(f"{kind}0")
        col, row = camera.world_to_pixel(s.poses[k][None, :3].astype(float))[0] / 8
        peak = np.unravel_index(maps[KINDS.index(kind)].argmax(), (16, 16))
        assert peak == (int(row), int(col)) and maps[KINDS.index(kind)].max() > 0.5
    assert maps[KINDS.index("block")].max() == 0  # none in the scene
    ball = s.slots.index("ball0")
    hidden = State(s.poses, s.held, s.slots, s.members, frozenset({ball}))
    assert object_maps(hidden, 16)[KINDS.index("ball")].max() == 0  # not seen: not drawn


def test_place_maps_find_the_clauses_subject_and_other_object(scene):
    from afford.words.data import place_maps
    from afford.words.facts import Fact

    scene.reset([O.upright("cup", -0.1, 0.25), O.upright("ball", 0.1, 0.25)])
    s = State.of_scene(scene)
    cup, ball = s.slots.index("cup0"), s.slots.index("ball0")
    maps = place_maps(s, Fact("left_of", cup, ball), 16)
    assert maps.shape == (2, 16, 16) and np.allclose(maps.sum((1, 2)), 1.0)
    expected = object_maps_peaks(s, (cup, ball))
    assert [np.unravel_index(m.argmax(), (16, 16)) for m in maps] == expected
    on_table = place_maps(s, Fact("on", ball, "table"), 16)
    assert on_table[1].sum() == 0  # a word, not an object: nothing to find
    hidden = State(s.poses, s.held, s.slots, s.members, frozenset({ball}))
    assert place_maps(hidden, Fact("left_of", ball, cup), 16)[0].sum() == 0  # not seen


def object_maps_peaks(s: State, slots) -> list[tuple[int, int]]:
    from afford.sim import camera

    cells = []
    for k in slots:
        col, row = camera.world_to_pixel(s.poses[k][None, :3].astype(float))[0] / 8
        cells.append((int(row), int(col)))
    return cells


def test_the_grounding_loss_is_low_on_the_named_objects_and_skips_missing_ones():
    import torch

    from afford.words.train import grounding_loss

    places = torch.zeros((2, 2, 4, 4))
    places[0, 0, 1, 2] = 1.0  # the subject at cell (1, 2); no other object (a word)
    places[1, 0, 3, 0] = places[1, 1, 0, 3] = 1.0
    right = torch.full((2, 2, 16), -10.0)
    right[0, 0, 1 * 4 + 2] = right[1, 0, 3 * 4 + 0] = right[1, 1, 0 * 4 + 3] = 10.0
    right.requires_grad_(True)
    loss = grounding_loss(right, places)
    assert float(loss.detach()) < 1e-6
    wrong = torch.zeros((2, 2, 16), requires_grad=True)
    bad = grounding_loss(wrong, places)
    assert float(bad.detach()) == pytest.approx(np.log(16), rel=1e-5)  # uniform maps: log(cells)
    bad.backward()
    assert float(wrong.grad[0, 1].abs().sum()) == 0.0  # the map with nothing to find: untaught


def test_the_shipped_agreement_model_ranks_the_state_a_sentence_describes_first(scene):
    """A hand-made pair: a cup on the block's left end, and the same cup on the table."""
    import torch

    from afford.images import to_chw
    from afford.planning.sentence_goal import load_agreement

    net = load_agreement()
    images = []
    for cup in (O.upright("cup", -0.09, 0.30, z=BLOCK_TOP_ON_TABLE), O.upright("cup", 0.12, 0.22)):
        scene.reset([O.upright("block", 0, 0.30), cup, O.upright("ball", 0.1, 0.38)])
        images.append(scene.observe())
    states = to_chw(np.stack(images).astype(np.float32))
    with torch.no_grad():
        on_block = net.statement_logprob(states, "the cup is on the block")
        on_table = net.statement_logprob(states, "the cup is on the table and the ball is on the table")
    assert on_block[0] > on_block[1] and on_table[1] > on_table[0]


def test_training_goals_with_grounded_maps_logs_each_loss(small_dataset, tmp_path):
    import json

    from afford.words.config import PRESETS
    from afford.words.train import train

    config = dataclasses.replace(
        PRESETS["tiny"], readout="attend", loss_objects=1.0, loss_ground=1.0, steps=6, log_every=2, threads=1
    )
    train(small_dataset, config, tmp_path, progress=False)
    logged = [json.loads(line) for line in (tmp_path / "log.jsonl").read_text().splitlines()]
    losses = [row for row in logged if "train/ground" in row]
    assert losses and all(np.isfinite(row["train/ground"]) and row["train/ground"] > 0 for row in losses)
    with pytest.raises(ValueError, match="readout=attend"):
        train(small_dataset, dataclasses.replace(config, readout="pool"), tmp_path / "pool", progress=False)


def test_a_model_given_the_geometric_read_loads_one_without_and_judges_alike_until_trained():
    import torch

    from afford.training.checkpoint import load_model_state
    from afford.words.config import PRESETS
    from afford.words.model import AgreementNet
    from afford.words.sentences import vocabulary

    torch.manual_seed(0)
    base = dataclasses.replace(PRESETS["tiny"], vocabulary=tuple(vocabulary()), readout="attend")
    before = AgreementNet(base).eval()
    after = AgreementNet(dataclasses.replace(base, geometry=True)).eval()
    load_model_state(after, {f"model.{k}": v for k, v in before.state_dict().items()}, "test")
    images = torch.rand((3, 4, 128, 128))
    ids = before.token_ids(["the cup is left of the ball", "the ball is behind the cup", "the cup is gone"])
    assert torch.allclose(before(images, ids), after(images, ids))
    with pytest.raises(ValueError, match="readout=attend"):
        AgreementNet(dataclasses.replace(base, readout="pool", geometry=True))


def test_the_shipped_agreement_model_reads_left_and_behind_on_a_hand_made_pair(scene):
    """The same two objects swapped: the clause about their order holds in one image only."""
    import torch

    from afford.images import to_chw
    from afford.planning.sentence_goal import load_agreement

    net = load_agreement()
    images = []
    for cup, ball in (((-0.1, 0.22), (0.08, 0.36)), ((0.08, 0.36), (-0.1, 0.22))):
        scene.reset([O.upright("cup", *cup), O.upright("ball", *ball), O.upright("block", 0.0, 0.46)])
        images.append(scene.observe())
    states = to_chw(np.stack(images).astype(np.float32))
    with torch.no_grad():
        left = net.statement_logprob(states, "the cup is left of the ball")
        front = net.statement_logprob(states, "the cup is in front of the ball")
        behind = net.statement_logprob(states, "the ball is behind the cup")
    for said in (left, front, behind):
        assert said[0] > np.log(0.5) > said[1]
