"""Dynamics nets judged together: the fusing rules on hand-made outcomes, and the ensemble
wherever one net goes (a weights folder, `afford eval dynamics`)."""

from __future__ import annotations

import dataclasses
import json

import numpy as np
import torch

from afford.objects.dynamics import PRESETS, ObjectDynamics, Outcomes, predict
from afford.objects.ensemble import DynamicsEnsemble, fuse
from afford.objects.state import axes_quat
from afford.objects.transitions import read_transitions
from afford.training.checkpoint import save_checkpoint

TINY = dataclasses.replace(PRESETS["tiny"], threads=1)
UPRIGHT = [1.0, 0.0, 0.0, 0.0]


def _pose(x: float, quat=UPRIGHT) -> list[float]:
    return [x, 0.0, 0.8, *quat]


def _member(first: list, second: list, probability: list[float], held: int = -1) -> Outcomes:
    """One member's two outcomes of one execution with two objects."""
    poses = np.array([[first, second], [first, second]], np.float32)[None]  # (1, K=2, 2, 7)
    return Outcomes(poses, np.array([[held, held]]), np.array([probability], np.float32))


def test_members_vote_and_a_moved_object_lands_at_the_movers_median():
    before = np.array([[_pose(0.0), _pose(0.5)]], np.float32)
    tipped = axes_quat(np.array([1.0, 0.0, 0.0]), np.array([0.0, 0.0, 1.0])).tolist()
    members = [
        # object 0 moved to 0.10 (tipped), object 1 still
        _member(_pose(0.10, tipped), _pose(0.5), [0.9, 0.1], held=0),
        # object 0 moved to 0.13, object 1 moved a little: outvoted
        _member(_pose(0.13), _pose(0.51), [0.2, 0.8], held=0),
        # object 0 moved to 0.30 (a stray landing), object 1 still
        _member(_pose(0.30), _pose(0.5), [0.7, 0.3]),
    ]
    fused = fuse(members, before)
    assert fused.poses.shape == (1, 2, 2, 7)
    # the median of the three movers' landings, with the axes of the one nearest it
    np.testing.assert_allclose(fused.poses[0, 0, 0, :3], [0.13, 0.0, 0.8], atol=1e-6)
    np.testing.assert_allclose(fused.poses[0, 0, 0, 3:], UPRIGHT, atol=1e-6)
    # two of three left object 1 where it was: copied exactly, as a still object is
    np.testing.assert_array_equal(fused.poses[0, :, 1], before[0, [1, 1]])
    assert fused.held.tolist() == [[0, 0]]
    # each member's likeliest outcome first: the mean of (0.9, 0.8, 0.7) and of (0.1, 0.2, 0.3)
    np.testing.assert_allclose(fused.probability, [[0.8, 0.2]], atol=1e-6)


def test_outcomes_are_fused_by_rank_and_a_split_vote_is_decided_among_those_that_act():
    before = np.array([[_pose(0.0), _pose(0.5)]], np.float32)
    gone = [np.nan] * 7

    def member(likely_x: float, other_x: float, probability: list[float]) -> Outcomes:
        # outcome 0 moves object 0 to other_x, outcome 1 to likely_x: the likelier is second
        poses = np.array([[_pose(other_x), _pose(0.5)], [_pose(likely_x), _pose(0.5)]], np.float32)[None]
        return Outcomes(poses, np.array([[-1, -1]]), np.array([probability], np.float32))

    fused = fuse([member(0.2, 0.3, [0.4, 0.6]), member(0.22, 0.3, [0.3, 0.7])], before)
    # each member's likelier outcome fused into the first, with its mean probability
    np.testing.assert_allclose(fused.poses[0, 0, 0, 0], 0.21, atol=1e-6)
    np.testing.assert_allclose(fused.poses[0, 1, 0, 0], 0.3, atol=1e-6)
    np.testing.assert_allclose(fused.probability, [[0.65, 0.35]], atol=1e-6)
    # two members say gone, two moved, one still: something happens, and it moves
    split = [_member(gone, _pose(0.5), [0.5, 0.5])] * 2 + [_member(_pose(0.2), _pose(0.5), [0.5, 0.5])] * 2
    fused = fuse([*split, _member(_pose(0.0), _pose(0.5), [0.5, 0.5], held=0)], before)
    np.testing.assert_allclose(fused.poses[0, 0, 0, :3], [0.2, 0.0, 0.8], atol=1e-6)
    # an object the fused poses put off the table is not held
    gone_held = [_member(gone, _pose(0.5), [0.5, 0.5], held=0)] * 2 + [
        _member(_pose(0.0), _pose(0.5), [0.5, 0.5])
    ]
    fused = fuse(gone_held, before)
    assert np.isnan(fused.poses[0, 0, 0, 0]) and fused.held.tolist() == [[-1, -1]]


def test_an_object_most_members_put_off_the_table_is_gone():
    before = np.array([[_pose(0.0), _pose(0.5)]], np.float32)
    gone = [np.nan] * 7
    members = [_member(gone, _pose(0.5), [0.5, 0.5]), _member(gone, _pose(0.5), [0.5, 0.5])]
    members.append(_member(_pose(0.2), _pose(0.5), [0.5, 0.5]))
    fused = fuse(members, before)
    assert np.isnan(fused.poses[0, :, 0]).all() and not np.isnan(fused.poses[0, :, 1]).any()


def _net(seed: int) -> ObjectDynamics:
    torch.manual_seed(seed)
    return ObjectDynamics(TINY)


def test_an_ensemble_of_one_net_is_that_net(pose_dataset):
    t = read_transitions(pose_dataset)
    net = _net(0)
    alone = predict(net, t.before, t.held_before, t.actions)
    ranked_first = alone.likeliest()[0]
    judged = DynamicsEnsemble([net]).outcomes(t.before, t.held_before, t.actions)
    np.testing.assert_array_equal(judged.likeliest()[0], ranked_first)
    np.testing.assert_allclose(np.sort(judged.probability, 1), np.sort(alone.probability, 1), atol=1e-6)


def test_a_weights_folder_with_members_loads_an_ensemble_and_eval_takes_several(
    pose_dataset, tmp_path, capsys
):
    from afford.cli.main import main
    from afford.shipped import DYNAMICS_FILE, OBJECT_MEMBERS_DIR, load_object_dynamics

    config = dataclasses.asdict(TINY)
    save_checkpoint(tmp_path / DYNAMICS_FILE, _net(0), "dynamics", config, step=1)
    assert isinstance(load_object_dynamics(tmp_path), ObjectDynamics)
    for k in (1, 2):
        save_checkpoint(
            tmp_path / OBJECT_MEMBERS_DIR / f"m{k}.safetensors", _net(k), "dynamics", config, step=1
        )
    ensemble = load_object_dynamics(tmp_path)
    assert isinstance(ensemble, DynamicsEnsemble) and len(ensemble) == 3
    t = read_transitions(pose_dataset)
    o = ensemble.outcomes(t.before, t.held_before, t.actions)
    assert o.poses.shape == (len(t), TINY.outcomes, *t.before.shape[1:])
    np.testing.assert_allclose(o.probability.sum(1), 1.0, atol=1e-5)
    files = [
        str(tmp_path / DYNAMICS_FILE),
        *(str(p) for p in sorted((tmp_path / OBJECT_MEMBERS_DIR).iterdir())),
    ]
    args = ["eval", "dynamics", "--weights", *files, "--data", str(pose_dataset), "--split", "all", "--json"]
    assert main(args) == 0
    assert json.loads(capsys.readouterr().out)["model"] == " + ".join(files)
