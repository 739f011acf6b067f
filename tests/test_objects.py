"""The object world model's data and dynamics: pose-only generation, the arm's path, the state
encoding, and the dynamics nets at tiny sizes."""

from __future__ import annotations

import copy
import dataclasses
import json

import numpy as np
import pytest
import torch

from afford.data.format import DataError, Dataset
from afford.data.generate import GenerateConfig, generate
from afford.data.shard import make_sequence
from afford.objects.dynamics import (
    PRESETS,
    DynamicsConfig,
    ObjectDynamics,
    encode_inputs,
    encode_targets,
    mixture_loss,
    predict,
)
from afford.objects.state import SLOT_KIND, axes_quat, quat_axes, slot_features
from afford.objects.transitions import read_transitions
from afford.sim.arm_path import PATH_POINTS, PATH_WIDTH

TINY = dataclasses.replace(PRESETS["tiny"], threads=1)


def test_pose_generator_gives_the_rendering_generators_states(scene):
    for i in range(2):
        with_images, _ = make_sequence(scene, 5, i, 4, images=True)
        poses_only, _ = make_sequence(scene, 5, i, 4, images=False)
        assert with_images.has_images and not poses_only.has_images
        np.testing.assert_array_equal(with_images.poses, poses_only.poses)
        np.testing.assert_array_equal(with_images.held, poses_only.held)
        np.testing.assert_array_equal(with_images.actions, poses_only.actions)
        np.testing.assert_array_equal(with_images.arm_paths, poses_only.arm_paths)
        assert poses_only.arm_paths.shape == (poses_only.length, PATH_POINTS, PATH_WIDTH)


def test_the_arm_path_reaches_down_to_what_it_grasps(scene):
    seq, _ = make_sequence(scene, 5, 0, 4, images=False)
    grasps = [t for t in range(seq.length) if seq.action(t).type == "grasp"]
    assert grasps
    for t in grasps:
        path, target = seq.arm_paths[t], seq.actions[t, 1:4]
        lowest = path[np.argmin(path[:, 2])]
        # the TCP comes down to the object's centre, above it in the plane, and ends home
        assert np.linalg.norm(lowest[:2] - target[:2]) < 0.01 and lowest[2] < target[2] + 0.05
        assert path[-1, 2] > 0.25 and 0.0 <= path[:, 4].min() and path[:, 4].max() <= 1.05


def test_a_pose_only_dataset_says_it_has_no_images(pose_dataset):
    data = Dataset(pose_dataset)
    assert data.manifest.generator["images"] is False
    seq = data.sequence(0)
    with pytest.raises(DataError, match="poses only"):
        seq.image(0)
    with pytest.raises(DataError, match="poses only"):
        generate(pose_dataset, GenerateConfig(sequences=8, seed=3, workers=1, shard_size=4), progress=False)
    t = read_transitions(pose_dataset)
    assert len(t) == sum(data.sequence(i).length for i in range(8))


def test_axes_give_back_the_quaternion():
    rng = np.random.default_rng(0)
    q = rng.normal(size=(50, 4))
    q /= np.linalg.norm(q, axis=1, keepdims=True)
    up, along = quat_axes(q)
    back = axes_quat(up, along)
    np.testing.assert_allclose(np.abs((back * q).sum(1)), 1.0, atol=1e-9)  # q and -q are one pose


def test_features_mark_absent_and_held_objects(pose_dataset):
    t = read_transitions(pose_dataset)
    f, present = slot_features(t.before, t.held_before)
    assert f.shape[:2] == t.before.shape[:2]
    assert np.all(f[~present] == 0)
    held_rows = np.nonzero(t.held_before >= 0)[0]
    assert len(held_rows)
    for i in held_rows:
        assert f[i, t.held_before[i], 1] == 1 and f[i, :, 1].sum() == 1


def test_dynamics_shapes_gradients_and_a_falling_loss(pose_dataset):
    torch.manual_seed(0)
    t = read_transitions(pose_dataset)
    config = dataclasses.replace(TINY, outcomes=2)
    net = ObjectDynamics(config)
    inputs = encode_inputs(t.before, t.held_before, t.actions)
    targets = encode_targets(t.before, t.after, t.held_after, config)
    out = net(inputs)
    n, s = t.before.shape[:2]
    assert out["dpos"].shape == (n, s, 2, 3) and out["outcome"].shape == (n, 2)
    opt = torch.optim.Adam(net.parameters(), lr=3e-3)
    losses = []
    for _ in range(60):
        loss, _ = mixture_loss(net(inputs), targets, config.spread)
        opt.zero_grad()
        loss.backward()
        losses.append(float(loss.detach()))
        opt.step()
    assert all(p.grad is not None for p in net.parameters())
    assert losses[-1] < 0.5 * losses[0]
    foreseen = predict(net, t.before, t.held_before, t.actions)
    assert foreseen.poses.shape == (n, 2, s, 7)


def test_the_gate_copies_still_objects_exactly(pose_dataset):
    t = read_transitions(pose_dataset)
    net = ObjectDynamics(TINY)
    for p in net.p.values():  # every object called still, and never gone or held
        last = p.head[-1]
        torch.nn.init.zeros_(last.weight)
        with torch.no_grad():
            last.bias.zero_()
            last.bias.view(TINY.outcomes, -1)[:, :3] = -20.0
    o = predict(net, t.before, t.held_before, t.actions)
    for k in range(TINY.outcomes):
        np.testing.assert_array_equal(o.poses[:, k], t.before)
    assert np.all(o.held == -1)
    np.testing.assert_allclose(o.probability.sum(1), 1.0, atol=1e-6)


def test_train_and_eval_dynamics_from_the_command_line(pose_dataset, tmp_path, capsys):
    from afford.cli.main import main

    run = tmp_path / "run"
    assert (
        main(
            [
                "train",
                "dynamics",
                "--data",
                str(pose_dataset),
                "--preset",
                "tiny",
                "--out",
                str(run),
                "--json",
            ]
        )
        == 0
    )
    assert (run / "last.safetensors").is_file()
    # the outcome temperature, fitted when training ended, is in the run and in the record
    record = json.loads(capsys.readouterr().out)
    assert (run / "calibration.json").is_file() and record["calibration"]["outcome_temperature"] > 0
    # a run's checkpoint takes the temperature fitted to its own step; an exported file its own
    from afford.objects.train import load_dynamics
    from afford.training.checkpoint import export_weights, read_checkpoint

    step = read_checkpoint(run / "best.safetensors", "dynamics")[1]["step"]
    (run / "calibration.json").write_text(json.dumps({"outcome_temperature": 3.0, "step": step}))
    assert load_dynamics(run / "best.safetensors").config.outcome_temperature == 3.0
    assert load_dynamics(run / "best.safetensors", calibrated=False).config.outcome_temperature == 1.0
    exported = run / "shipped.safetensors"
    export_weights(
        run / "best.safetensors",
        exported,
        "dynamics",
        config={"outcome_temperature": 2.0},
        config_cls=DynamicsConfig,
    )
    assert load_dynamics(exported).config.outcome_temperature == 2.0
    (run / "calibration.json").write_text(json.dumps({"outcome_temperature": 3.0, "step": step + 1}))
    assert load_dynamics(run / "best.safetensors").config.outcome_temperature == 1.0
    assert (
        main(
            [
                "eval",
                "dynamics",
                "--weights",
                str(run / "last.safetensors"),
                "--data",
                str(pose_dataset),
                "--split",
                "all",
                "--json",
            ]
        )
        == 0
    )
    report = json.loads(capsys.readouterr().out)
    assert report["executions"] > 0 and "still" in report["groups"]
    # a weights file of another kind: one line
    from afford.shipped import WEIGHTS

    assert (
        main(
            [
                "eval",
                "dynamics",
                "--weights",
                str(WEIGHTS / "prediction.safetensors"),
                "--data",
                str(pose_dataset),
            ]
        )
        == 2
    )
    assert "not a dynamics one" in capsys.readouterr().err


def test_a_dynamics_run_started_from_weights_begins_where_they_left_off(pose_dataset, tmp_path):
    from afford.objects.train import train
    from afford.training.checkpoint import read_checkpoint

    run = tmp_path / "run"
    train([pose_dataset], TINY, run, progress=False)
    # with no step size, a run started from those weights ends where it began
    again = tmp_path / "again"
    train(
        [pose_dataset],
        dataclasses.replace(TINY, steps=1, lr=0.0),
        again,
        progress=False,
        init=run / "best.safetensors",
    )
    first, _ = read_checkpoint(run / "best.safetensors", "dynamics")
    then, _ = read_checkpoint(again / "last.safetensors", "dynamics")
    weights = [k for k in first if k.startswith("model.")]
    assert weights and all(torch.equal(first[k], then[k]) for k in weights)


def test_a_temperature_is_fitted_back_and_predict_applies_it(pose_dataset):
    from afford.objects.calibration import fit_temperature, log_loss

    rng = np.random.default_rng(0)
    logits = rng.normal(0, 3, (4000, 2))
    z = logits / 2.0  # the truth is twice as unsure as the logits say
    p = np.exp(z) / np.exp(z).sum(1, keepdims=True)
    won = (rng.random(4000) < p[:, 1]).astype(int)
    shares = np.eye(2)[won]
    fit = fit_temperature(logits, shares)
    assert 1.8 < fit.outcome_temperature < 2.2
    assert fit.nll_calibrated < fit.nll_raw == pytest.approx(log_loss(logits, shares, 1.0))

    t = read_transitions(pose_dataset, None)
    torch.manual_seed(0)
    net = ObjectDynamics(dataclasses.replace(TINY, outcomes=2))
    args = (t.before[:6], t.held_before[:6], t.actions[:6])
    sure = predict(net, *args)
    net.config.outcome_temperature = 4.0
    unsure = predict(net, *args)
    # the same outcomes in the same order, their probabilities nearer one half
    np.testing.assert_array_equal(sure.poses, unsure.poses)
    np.testing.assert_array_equal(sure.probability.argmax(1), unsure.probability.argmax(1))
    assert np.all(np.abs(unsure.probability - 0.5) <= np.abs(sure.probability - 0.5) + 1e-7)


def test_the_simulator_from_true_objects_gives_the_recorded_next_state(pose_dataset, scene):
    from afford.objects.measure import pixel_error
    from afford.objects.simulated import simulate

    t = read_transitions(pose_dataset)
    t = t.subset(np.arange(min(12, len(t))))
    o = simulate(scene, t.before, t.held_before, t.actions)
    np.testing.assert_array_equal(o.held[:, 0], t.held_after)
    there = ~np.isnan(t.after[..., 0])
    np.testing.assert_array_equal(np.isnan(o.poses[:, 0, :, 0]), ~there)
    err = pixel_error(o.poses[:, 0][there], t.after[there])
    # canonical steps land where they did; a side effect may differ a little (a scene rebuilt
    # from float32 poses, at rest, is not bit for bit the recorded one)
    assert np.median(err) < 0.05 and np.mean(err < 1.0) > 0.9


def test_a_shard_without_masks_in_a_masked_dataset_is_made_again(tmp_path):
    from dataclasses import replace

    from afford.data.format import read_shard, shard_path, write_shard

    root = tmp_path / "m"
    config = GenerateConfig(sequences=2, seed=3, workers=1, shard_size=1, masks=True)
    generate(root, config, progress=False)
    data = Dataset(root)
    assert data.sequence(0).masks.shape == (data.sequence(0).length + 1, 128, 128)
    path = shard_path(root, 0)
    write_shard(path, [replace(s, masks=None) for s in read_shard(path, data.slots)])
    with pytest.raises(DataError, match="no instance masks"):
        Dataset(root).sequence(0)
    report = generate(root, config, progress=False)
    assert len(report.remade) == 1 and "no instance masks" in report.remade[0]
    assert Dataset(root).sequence(0).masks is not None


def test_perception_shapes_posture_targets_and_a_falling_loss(tmp_path):
    from afford.objects.perception import (
        HEADS,
        NO_POSTURE,
        PerceptionNet,
        fold_batch_norms,
        loss,
        targets,
    )
    from afford.objects.perception import PRESETS as SEEING
    from afford.objects.perception_train import batch_of, states_of
    from afford.objects.state import POSTURES

    root = tmp_path / "m"
    generate(root, GenerateConfig(sequences=2, seed=3, workers=1, shard_size=2, masks=True), progress=False)
    data = Dataset(root)
    config = SEEING["tiny"]
    images, t = batch_of(data, states_of(data, None)[:4], config)
    torch.manual_seed(0)
    net = PerceptionNet(config)
    out = net(images)
    assert {k: v.shape[1] for k, v in out.items()} == HEADS
    # posture is a class on the pixels of cups, supports and the block, and on no others
    seq = data.sequence(0)
    masks = seq.masks[:1]
    t0 = targets(masks, seq.poses[:1], seq.held[:1], config.sigma_px)
    ball = np.isin(masks[0], np.flatnonzero(SLOT_KIND == 1))
    assert (t0["posture"][0][torch.from_numpy(ball)] == NO_POSTURE).all()
    objects = (masks[0] >= 0) & ~ball
    assert objects.any() and (t0["posture"][0][torch.from_numpy(objects)] < len(POSTURES)).all()
    assert (t0["posture"][0][torch.from_numpy(masks[0] < 0)] == NO_POSTURE).all()
    opt = torch.optim.Adam(net.parameters(), lr=3e-3)
    first = first_posture = None
    for _ in range(30):
        total, parts = loss(net(images), t)
        opt.zero_grad()
        total.backward()
        assert all(p.grad is not None for p in net.parameters() if p.requires_grad)
        opt.step()
        first = first if first is not None else float(total.detach())
        first_posture = first_posture if first_posture is not None else parts["posture"]
    assert float(total.detach()) < 0.8 * first and parts["posture"] < first_posture
    # inference folds each batch norm into its convolution: the same outputs, no norms left
    net.eval()
    with torch.no_grad():
        before = net(images)
        folded = fold_batch_norms(copy.deepcopy(net))
        after = folded(images)
    assert not any(isinstance(m, torch.nn.BatchNorm2d) for m in folded.modules())
    for key, value in before.items():
        assert torch.allclose(value, after[key], atol=1e-4), key


@pytest.mark.parametrize("name", ["upright", "tipped", "lying"])
def test_an_up_axis_is_made_to_agree_with_a_posture(name):
    from afford.objects.state import fit_posture, posture

    for up in ([0.0, 0.0, 1.0], [0.6, 0.0, 0.8], [0.1, 0.99, 0.05], [0.5, 0.5, -0.7]):
        fitted = fit_posture(np.array(up), name)
        assert posture(float(fitted[2])) == name
        assert np.isclose(np.linalg.norm(fitted), 1.0)
        if posture(float(np.array(up)[2] / np.linalg.norm(up))) == name:  # agrees: kept
            np.testing.assert_allclose(fitted, np.array(up) / np.linalg.norm(up))
        elif name != "upright" and np.linalg.norm(up[:2]) > 0:  # its direction over the table kept
            flat = np.array(up[:2]) / np.linalg.norm(up[:2])
            np.testing.assert_allclose(fitted[:2] / np.linalg.norm(fitted[:2]), flat, atol=1e-9)
