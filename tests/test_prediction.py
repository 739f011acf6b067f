"""Prediction pathway: shapes, eq. (3), routing by affordance type, SignSGD, learning."""

from __future__ import annotations

import numpy as np
import pytest
import torch

from afford.prediction.config import PRESETS
from afford.prediction.model import (
    PredictionNet,
    affordance_pixel,
    apply_difference,
    clamped_tanh,
    normalise_latent,
)
from afford.prediction.train import sequence_loss
from afford.sim import camera
from afford.sim.affordance import encode_affordance
from afford.sim.affordances import Affordance
from afford.training.fields import with_fields
from afford.training.signsgd import SignSGD

TINY = PRESETS["tiny"]


def actions(*affs: Affordance) -> torch.Tensor:
    return torch.from_numpy(np.stack([encode_affordance(a) for a in affs]))


def test_rollout_shapes_and_range():
    net = PredictionNet(TINY)
    images = torch.rand(3, 4, 128, 128)
    acts = torch.stack(
        [
            actions(
                Affordance("grasp", (0, 0.3, 0.02), 0, True), Affordance("place", (0.1, 0.3, 0.06), 0, True)
            )
        ]
        * 3
    )
    out = net.rollout(images, acts)
    assert out.shape == (3, 2, 4, 128, 128)
    assert out.min() >= 0 and out.max() <= 1


def test_latent_normalisation_keeps_norm_below_one():
    a = torch.randn(5, 16) * 100
    assert torch.all(normalise_latent(a).norm(dim=-1) < 1)


def test_eq3_mask_zero_keeps_mask_one_takes():
    state = torch.rand(2, 4, 8, 8)
    new = torch.rand(2, 4, 8, 8)
    keep = apply_difference(state, torch.cat([new, torch.zeros(2, 1, 8, 8)], 1))
    take = apply_difference(state, torch.cat([new, torch.ones(2, 1, 8, 8)], 1))
    assert torch.equal(keep, state) and torch.allclose(take, new)
    half = apply_difference(state, torch.cat([new, torch.full((2, 1, 8, 8), 0.5)], 1))
    assert torch.allclose(half, (state + new) / 2)


def test_clamped_tanh_closes_exactly_and_still_passes_a_gradient():
    x = torch.tensor([-3.0, -0.1, 0.5, 4.0], requires_grad=True)
    y = clamped_tanh(x)
    assert y[0] == 0 and y[1] == 0 and torch.isclose(y[2], torch.tanh(torch.tensor(0.5)))
    y.sum().backward()
    # A closed mask pixel (x < 0) must still be able to open: tanh's gradient, not zero.
    assert torch.allclose(x.grad, 1 - torch.tanh(x.detach()) ** 2, atol=1e-6)


def test_each_example_goes_through_its_own_type_module():
    torch.manual_seed(0)
    net = PredictionNet(TINY).eval()
    image = torch.rand(1, 4, 128, 128)
    latent, memory = net.encode(image)
    grasp = actions(Affordance("grasp", (0, 0.3, 0.02), 0, True))
    turn = actions(Affordance("turn", (0, 0.3, 0.02), 0, False, 90))
    with torch.no_grad():
        batch = net.step(
            torch.cat([latent] * 2),
            torch.cat([memory] * 2),
            image.repeat(2, 1, 1, 1),
            torch.cat([grasp, turn]),
        )
        alone = net.step(latent, memory, image, turn)
        # Silence the turn module: only the turn example may change.
        for p in net.modules_by_type[2].parameters():
            p.zero_()
        silenced = net.step(
            torch.cat([latent] * 2),
            torch.cat([memory] * 2),
            image.repeat(2, 1, 1, 1),
            torch.cat([grasp, turn]),
        )
    assert torch.allclose(batch[0][1], alone[0][0], atol=1e-6)  # mixed batch == one at a time
    assert torch.allclose(silenced[0][0], batch[0][0], atol=1e-6)
    assert not torch.allclose(silenced[0][1], batch[0][1], atol=1e-6)


def test_affordance_pixel_reads_the_projected_pixel():
    image = torch.zeros(1, 4, 128, 128)
    pos = np.array([0.07, 0.33, 0.05])
    r, c = camera.pixel_index(pos)
    image[0, :, r, c] = torch.tensor([0.1, 0.2, 0.3, 0.4])
    got = affordance_pixel(image, torch.tensor(pos, dtype=torch.float32)[None])
    assert torch.allclose(got[0], torch.tensor([0.1, 0.2, 0.3, 0.4]))


def test_no_pixel_input_zeroes_it():

    net = PredictionNet(with_fields(TINY, pixel_input=False))
    vec = net.action_vector(actions(Affordance("grasp", (0, 0.3, 0.02), 0, True)), torch.rand(1, 4, 128, 128))
    assert vec.shape == (1, 9) and torch.all(vec[0, 5:] == 0)


def test_signsgd_moves_each_weight_by_lr_against_its_gradient_sign():
    w = torch.nn.Parameter(torch.tensor([1.0, -2.0, 3.0]))
    opt = SignSGD([w], lr=0.1)
    (w * torch.tensor([5.0, -0.01, 0.0])).sum().backward()
    opt.step()
    assert torch.allclose(w.detach(), torch.tensor([0.9, -1.9, 3.0]))
    with pytest.raises(ValueError):
        SignSGD([w], lr=0)


@pytest.mark.parametrize("preset", ["tiny", "tiny-dense"])
def test_loss_falls_on_a_tiny_batch(preset):
    torch.manual_seed(0)
    net = PredictionNet(PRESETS[preset])
    grasp, place = (
        Affordance("grasp", (0, 0.3, 0.02), 0, True),
        Affordance("place", (0.1, 0.3, 0.06), 0, True),
    )
    # A grey table; the grasp puts a bright square down where it acts, the place a dark one.
    images = torch.full((2, 3, 4, 128, 128), 0.5)
    for k, (a, value) in enumerate(((grasp, 0.9), (place, 0.1))):
        r, c = camera.pixel_index(np.array(a.position))
        images[:, k + 1 :, :, r - 10 : r + 10, c - 10 : c + 10] = value
    acts = torch.stack([actions(grasp, place)] * 2)
    steps = torch.tensor([2, 1])
    opt = torch.optim.Adam(net.parameters(), lr=1e-2)
    losses = []
    for _ in range(40):
        loss = sequence_loss(net, images, acts, steps)
        opt.zero_grad()
        loss.backward()
        opt.step()
        losses.append(float(loss.detach()))
    assert losses[-1] < 0.5 * losses[0]


def test_spatial_action_maps_peak_at_the_affordance_pixel():
    from afford.prediction.spatial import action_maps

    net = PredictionNet(TINY)
    a = Affordance("turn", (0.07, 0.33, 0.025), 30.0, False, -90)
    rows = actions(a)
    image = torch.rand(1, 4, 128, 128)
    vector = net.action_vector(rows, image)
    pixel = camera.world_to_pixel(rows[:, 1:4])
    maps = action_maps(vector, pixel, 16, 0.8)[0]  # (channels, 16, 16)
    blob = maps[0]
    row, col = divmod(int(blob.argmax()), 16)
    assert (row, col) == (int(pixel[0, 1]) // 8, int(pixel[0, 0]) // 8)
    assert blob.max() > 0.6 and blob[0, 0] < 1e-3  # a peak there, nothing far away
    # Each value map is the blob times its value: cos/sin of the angle, the turn, the pixel's RGBD.
    at = maps[:, row, col] / blob[row, col]
    assert torch.allclose(
        at[1:3], torch.tensor([np.cos(np.radians(30)), np.sin(np.radians(30))]).float(), atol=1e-5
    )
    assert torch.isclose(at[5], torch.tensor(-1.0))
    assert torch.allclose(at[7:], affordance_pixel(image, rows[:, 1:4])[0])


def test_shipped_weights_predict_a_grasp_at_the_object_and_in_the_gripper(scene):
    from scenarios import find

    from afford.prediction.evaluate import load_net
    from afford.shipped import PREDICTION_FILE, WEIGHTS
    from afford.sim.scene import ObjectSpec

    net, config = load_net(WEIGHTS / PREDICTION_FILE)
    assert config.model.architecture == "spatial"
    scene.reset([ObjectSpec.upright("cup", 0.10, 0.36), ObjectSpec.upright("support", -0.12, 0.30)])
    image = scene.observe()
    grasp = find(scene.affordances(), "grasp", (0.10, 0.36))
    x = torch.from_numpy(image).permute(2, 0, 1)[None]
    with torch.no_grad():
        predicted = net.rollout(x, actions(grasp)[None])[0, 0].permute(1, 2, 0).numpy()
    changed = np.abs(predicted - image).max(-1) > 0.1
    # Where a change belongs: around the cup (it leaves) and in the gripper's part of the
    # image (it arrives there), the true next state's changes marking the gripper's part.
    scene.execute(grasp)
    truth_changed = np.abs(scene.observe() - image).max(-1) > 0.02
    r, c = camera.pixel_index(np.array(grasp.position))
    rows, cols = np.mgrid[:128, :128]
    at_cup = np.hypot(rows - r, cols - c) < 14
    gripper = np.zeros_like(at_cup)
    gr, gc = np.nonzero(truth_changed & ~at_cup)
    gripper[max(gr.min() - 6, 0) : gr.max() + 7, max(gc.min() - 6, 0) : gc.max() + 7] = True
    assert changed[at_cup].sum() > 40  # the cup is erased from where it stood
    assert (changed & gripper).sum() > 40  # and drawn in the gripper
    assert (changed & ~at_cup & ~gripper).sum() < 0.03 * changed.sum()  # nothing changes elsewhere
