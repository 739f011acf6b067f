"""Recognition net: shapes, target assignment, decode of encoded targets, suppression, learning."""

from __future__ import annotations

import numpy as np
import pytest
import torch

from afford.metrics import Tally, matches
from afford.recognition.config import PRESETS
from afford.recognition.model import REG, RecognitionNet, fused_for_inference
from afford.recognition.targets import build_targets, decode, loss, quality, suppress
from afford.sim import camera
from afford.sim.affordance import Detection, encode_affordance
from afford.sim.affordances import Affordance
from afford.training.checkpoint import CheckpointError, save_checkpoint

TINY = PRESETS["tiny"]


def rows(*affs: Affordance) -> np.ndarray:
    return np.stack([encode_affordance(a) for a in affs])


def test_output_shape_and_bad_input():
    net = RecognitionNet(TINY)
    out = net(torch.rand(2, 4, 128, 128))
    assert out.shape == (2, 4, 32, 32, 1 + 3 + 3 * REG)
    with pytest.raises(ValueError, match=r"\(B, 4, 128, 128\)"):
        net(torch.rand(2, 3, 128, 128))


def test_target_goes_to_its_cell_neighbours_and_angle_anchor():
    a = Affordance("grasp", (0.05, 0.30, 0.04), 100.0, False)
    t = build_targets([rows(a)], TINY)
    col, row = camera.world_to_pixel(np.array(a.position)) / TINY.stride
    cx, cy = int(col), int(row)
    anchor = 1  # 100 degrees is within 45 of the 90-degree anchor
    cells = {(int(y), int(x)) for y, x in zip(*np.nonzero(t.obj[0, anchor].numpy()), strict=True)}
    nx = cx - 1 if col - cx < 0.5 else cx + 1
    ny = cy - 1 if row - cy < 0.5 else cy + 1
    assert cells == {(cy, cx), (cy, nx), (ny, cx)}
    assert t.obj[0].sum() == 3 and t.obj[0, 0].sum() == 0
    reg = t.reg[0, anchor, cy, cx, 0]
    assert reg[0] == pytest.approx(col - cx, abs=1e-4) and reg[1] == pytest.approx(row - cy, abs=1e-4)
    assert reg[2] == pytest.approx(10.0 / 45.0)  # angle offset from the anchor, in units of 45
    assert t.types[0, anchor, cy, cx].tolist() == [1.0, 0.0, 0.0]


def _raw_from_targets(t, config) -> torch.Tensor:
    """The head output that decodes to exactly the targets (inverting each activation)."""
    b, a, g = t.obj.shape[:3]
    n_types = len(config.types)
    raw = torch.full((b, a, g, g, 1 + n_types + n_types * REG), -20.0)
    raw[..., 0] = torch.where(t.obj > 0, 20.0, -20.0)
    raw[..., 1 : 1 + n_types] = torch.where(t.types > 0, 20.0, -20.0)
    reg = torch.zeros((b, a, g, g, n_types, REG))
    xy = ((t.reg[..., :2] + 0.5) / 2).clamp(1e-6, 1 - 1e-6)
    reg[..., :2] = torch.log(xy / (1 - xy))
    reg[..., 2] = torch.atanh(t.reg[..., 2].clamp(-0.999999, 0.999999))
    reg[..., 3] = t.reg[..., 3]
    reg[..., 4] = torch.where(t.reg[..., 4] > 0.5, 20.0, -20.0)
    raw[..., 1 + n_types :] = reg.flatten(-2)
    return raw


def test_decode_inverts_the_targets():
    truth = [
        Affordance("grasp", (0.05, 0.30, 0.025), 30.0, False),
        Affordance("turn", (0.05, 0.30, 0.025), 30.0, False),  # same point, another type
        Affordance("place", (-0.12, 0.22, 0.06), 270.0, True),
        Affordance("grasp", (0.15, 0.40, 0.0425), 180.0, True),
    ]
    raw = _raw_from_targets(build_targets([rows(*truth)], TINY), TINY)
    dets = suppress(decode(raw, TINY, 0.5)[0], 0.025, 10.0)
    assert len(dets) == len(truth)
    for t in truth:
        found = [d.affordance for d in dets if d.affordance.type == t.type and matches(d.affordance, t)]
        assert found, t
        assert np.allclose(found[0].position, t.position, atol=1e-4)
        assert found[0].symmetric == t.symmetric
        assert abs((found[0].angle - t.angle + 180) % 360 - 180) < 1e-3


def test_suppression_keeps_the_most_confident():
    def det(x, angle, score, sym=False, kind="grasp"):
        return Detection(Affordance(kind, (x, 0.3, 0.02), angle, sym), score)

    kept = suppress(
        [
            det(0.0, 0, 0.6),
            det(0.01, 2, 0.9),  # duplicate of the first: near, same angle; more confident
            det(0.01, 90, 0.8),  # same point, another angle: kept
            det(0.1, 0, 0.7),  # far: kept
            det(0.005, 0, 0.5, kind="turn"),  # another type: kept
            det(0.2, 0, 0.7, sym=True),
            det(0.205, 90, 0.6, sym=True),  # symmetric: any angle is a duplicate
        ],
        0.025,
        10.0,
    )
    assert [round(d.score, 1) for d in kept] == [0.9, 0.8, 0.7, 0.7, 0.5]


def test_tally_counts_hits_and_spurious():
    truth = [Affordance("grasp", (0, 0.3, 0.02), 0, False), Affordance("place", (0.1, 0.3, 0.06), 0, True)]
    dets = [
        Detection(Affordance("grasp", (0.01, 0.3, 0.02), 4.0, False), 0.9),  # hit (1 cm, 4 degrees)
        Detection(Affordance("place", (0.1, 0.3, 0.06), 90.0, True), 0.9),  # hit: symmetric truth
        Detection(Affordance("grasp", (0.0, 0.3, 0.02), 20.0, False), 0.9),  # spurious: 20 degrees off
    ]
    tally = Tally()
    tally.add(dets, truth)
    assert tally.recall == 1.0 and tally.spurious == 1


def test_loss_falls_on_a_tiny_batch():
    torch.manual_seed(0)
    net = RecognitionNet(TINY)
    images = torch.rand(2, 4, 128, 128)
    targets = build_targets(
        [
            rows(Affordance("grasp", (0.05, 0.30, 0.04), 0.0, True)),
            rows(Affordance("turn", (-0.05, 0.25, 0.025), 45.0, False)),
        ],
        TINY,
    )
    opt = torch.optim.Adam(net.parameters(), lr=3e-3)
    losses = []
    for _ in range(25):
        total, _ = loss(net(images), targets, TINY)
        opt.zero_grad()
        total.backward()
        opt.step()
        losses.append(float(total.detach()))
    assert losses[-1] < 0.5 * losses[0]


def test_type_weights_scale_that_types_terms_only():
    from dataclasses import replace

    torch.manual_seed(0)
    raw = RecognitionNet(TINY)(torch.rand(1, 4, 128, 128)).detach()
    turn = build_targets([rows(Affordance("turn", (-0.05, 0.25, 0.025), 45.0, False))], TINY)
    grasp = build_targets([rows(Affordance("grasp", (0.05, 0.30, 0.04), 0.0, True))], TINY)
    heavy = replace(TINY, type_weights=(1.0, 1.0, 3.0))
    _, plain_turn = loss(raw, turn, TINY)
    _, heavy_turn = loss(raw, turn, heavy)
    for term in ("type", "xy", "angle", "z", "sym"):
        assert heavy_turn[term] == pytest.approx(3 * plain_turn[term], rel=1e-5)
    assert heavy_turn["conf"] > plain_turn["conf"]  # its positive cells weigh 3, negatives 1
    assert loss(raw, grasp, heavy)[0] == pytest.approx(float(loss(raw, grasp, TINY)[0]), rel=1e-6)


def test_quality_is_one_where_the_regression_is_exact_and_falls_with_the_angle_error():
    t = build_targets([rows(Affordance("turn", (-0.05, 0.25, 0.025), 45.0, False))], TINY)
    xy, angle = t.reg[..., :2].clone(), t.reg[..., 2].clone()
    q = quality(xy, angle, t, TINY)
    assert torch.all(q[t.obj > 0] == 1) and torch.all(q[t.obj == 0] == 0)
    off = quality(xy, angle + TINY.quality_degrees / 45.0, t, TINY)  # one width off
    assert torch.allclose(off[t.obj > 0], torch.tensor(np.exp(-0.5), dtype=torch.float32))
    sym = build_targets([rows(Affordance("grasp", (0.05, 0.30, 0.04), 0.0, True))], TINY)
    assert torch.all(quality(sym.reg[..., :2], sym.reg[..., 2] + 0.5, sym, TINY)[sym.obj > 0] == 1)


def test_folded_batch_norms_give_the_same_outputs():
    torch.manual_seed(0)
    net = RecognitionNet(TINY)
    with torch.no_grad():
        for _ in range(3):  # running statistics away from their initial 0 / 1
            net(torch.rand(4, 4, 128, 128) * 2)
        for m in net.modules():
            if isinstance(m, torch.nn.BatchNorm2d):
                m.weight.uniform_(0.5, 1.5)
                m.bias.uniform_(-0.2, 0.2)
    net.eval()
    fused = fused_for_inference(net)
    assert not any(isinstance(m, torch.nn.BatchNorm2d) for m in fused.stem.modules())
    x = torch.rand(2, 4, 128, 128)
    with torch.no_grad():
        assert torch.allclose(fused(x), net(x), atol=1e-4, rtol=1e-4)


def test_checkpoint_errors(tmp_path):
    from afford.recognition.infer import load_net

    bad = tmp_path / "bad.safetensors"
    bad.write_bytes(b"not a checkpoint at all")
    with pytest.raises(CheckpointError, match="not a readable"):
        load_net(bad)
    with pytest.raises(CheckpointError, match="no such checkpoint"):
        load_net(tmp_path / "missing.safetensors")
    from dataclasses import asdict

    other = tmp_path / "other.safetensors"
    save_checkpoint(other, RecognitionNet(TINY), "prediction", asdict(TINY), 0)
    with pytest.raises(CheckpointError, match="prediction checkpoint"):
        load_net(other)
    mismatched = tmp_path / "mismatched.safetensors"
    config = asdict(TINY) | {"widths": [8, 8, 8, 8]}
    save_checkpoint(mismatched, RecognitionNet(TINY), "recognition", config, 0)
    with pytest.raises(CheckpointError, match="architecture"):
        load_net(mismatched)
    good = tmp_path / "good.safetensors"
    save_checkpoint(good, RecognitionNet(TINY), "recognition", asdict(TINY), 3)
    net, config, meta = load_net(good)
    assert meta["step"] == 3 and config == TINY


def test_the_operating_point_is_the_best_recall_within_the_spurious_budget():
    from afford.recognition.evaluate import SPURIOUS_BUDGET, operating_point

    def row(th, recall, spurious, net):
        return {"threshold": th, "recall": recall, "spurious_per_image": spurious, "net": net}

    sweep = [row(0.4, 0.98, SPURIOUS_BUDGET + 0.03, 900), row(0.5, 0.97, SPURIOUS_BUDGET, 880)]
    sweep.append(row(0.6, 0.95, SPURIOUS_BUDGET - 0.05, 860))
    assert operating_point(sweep) == 0.5  # the most hits net of spurious would be 0.4
    over = [row(0.4, 0.98, 0.5, 900), row(0.5, 0.97, 0.4, 910)]
    assert operating_point(over) == 0.5  # nothing within the budget: the most net hits
