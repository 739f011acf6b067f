"""Effect labels (data/effects.py) on scripted scenes: each execution run in the simulator and
labelled from the true poses before and after, as the dataset stores them."""

import numpy as np
from scenarios import BLOCK_TOP_ON_TABLE, block_on_support, find
from test_physics import BESIDE

from afford.data import effects as fx
from afford.data.shard import pose_array
from afford.sim.affordance import encode_affordance
from afford.sim.constants import BALL
from afford.sim.scene import ObjectSpec as O


def labelled(scene, kind: str, near, turn: int = 0) -> fx.StepEffects:
    """Execute the affordance of `kind` nearest `near` and label what it did."""
    names = [n for n, _ in scene.slots]
    slot = lambda: names.index(scene.held) if scene.held else -1  # noqa: E731
    a = find(scene.affordances(), kind, near)
    if turn:
        a = a.with_turn(turn)
    before, held_before = pose_array(scene), slot()
    assert scene.execute(a).executed
    return fx.step_effects(before, pose_array(scene), held_before, slot(), encode_affordance(a), tuple(names))


def named(scene, step: fx.StepEffects) -> set[tuple[str, str]]:
    names = [n for n, _ in scene.slots]
    return {(e.kind, names[e.slot]) for e in step.effects}


def test_a_plain_grasp_is_canonical(scene):
    scene.reset([O.upright("block", 0, 0.30, 90), O.upright("cup", -0.12, 0.22)])
    step = labelled(scene, "grasp", (-0.12, 0.22))
    assert step.canonical and step.type == "grasp"
    assert [n for n, _ in scene.slots][step.acted] == "cup0"


def test_a_place_on_a_support_is_canonical(scene):
    scene.reset([O.upright("support", 0.12, 0.38), O.upright("ball", -0.1, 0.22)])
    labelled(scene, "grasp", (-0.1, 0.22))
    step = labelled(scene, "place", (0.12, 0.38))
    assert step.canonical, step.effects


def test_a_sweep_pushes_a_ball_away(scene):
    scene.reset([O.upright("block", 0, 0.30), O.upright("ball", 0.10, 0.30 + 0.03 + BALL.radius + 0.008)])
    step = labelled(scene, "turn", (0, 0.30), turn=90)
    assert named(scene, step) & {("pushed", "ball0"), ("off the table", "ball0")}
    assert not step.canonical and step.affected == [[n for n, _ in scene.slots].index("ball0")]


def test_a_ball_on_the_turned_block_rolls_off(scene):
    scene.reset([O.upright("block", 0, 0.30), O.upright("ball", 0.09, 0.30, z=BLOCK_TOP_ON_TABLE)])
    step = labelled(scene, "turn", (0, 0.30), turn=90)
    # It rode on the block and no longer does: not carried.
    assert named(scene, step) & {("pushed", "ball0"), ("off the table", "ball0")}
    assert ("carried", "ball0") not in named(scene, step)


def test_a_turning_block_topples_a_cup(scene):
    scene.reset([O.upright("block", 0, 0.30), O.upright("cup", 0.11, BESIDE + 0.004)])
    step = labelled(scene, "turn", (0, 0.30), turn=90)
    assert ("toppled", "cup0") in named(scene, step)


def test_a_cup_on_the_block_is_carried_by_a_turn(scene):
    scene.reset([O.upright("block", 0, 0.30), O.upright("cup", 0.09, 0.30, z=BLOCK_TOP_ON_TABLE)])
    step = labelled(scene, "turn", (0, 0.30), turn=90)
    assert named(scene, step) == {("carried", "cup0")}


def test_a_place_on_an_overhang_tips_the_block_and_the_cup_falls(scene):
    block_on_support(scene, -0.02, [O.upright("cup", 0.1, 0.2)])
    labelled(scene, "grasp", (0.1, 0.2))
    step = labelled(scene, "place", (0.09, 0.30))
    kinds = named(scene, step)
    assert ("block tips", "block0") in kinds
    assert ("placed falls", "cup0") in kinds or ("placed slides", "cup0") in kinds


def test_summary_labels_match_sequence_labels(small_dataset):
    from afford.data.format import Dataset, shard_path, shard_summary

    data = Dataset(small_dataset)
    by_summary = [
        steps
        for k in range(data.manifest.n_shards)
        for steps in fx.summary_effects(shard_summary(shard_path(data.root, k)), data.slots)
    ]
    by_sequence = [fx.sequence_effects(s) for s in data.sequences()]
    assert by_summary == by_sequence
    assert sum(len(s) for s in by_sequence) > 0


def test_tilt_of_a_quarter_turn_about_x_is_90_degrees():
    upright = np.array([0, 0, 0, 1, 0, 0, 0], dtype=float)
    on_side = np.array([0, 0, 0, np.cos(np.pi / 4), np.sin(np.pi / 4), 0, 0])
    assert abs(fx.tilt_deg(upright, on_side) - 90) < 1e-6
    assert fx.tilt_deg(upright, upright) == 0
