"""Dataset generation: crash safety, resumption, determinism, corrupt shards, readers, augmentation."""

from __future__ import annotations

import json
import os
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
from conftest import SMALL_SEED  # noqa: E402
from conftest import SMALL_SEQUENCES as N  # noqa: E402
from conftest import SMALL_SHARD as SHARD  # noqa: E402

from afford.cli.main import main
from afford.data.augment import NO_AUGMENT, AugmentConfig, augment
from afford.data.format import (
    MANIFEST,
    DataError,
    Dataset,
    shard_path,
    verify,
)
from afford.data.generate import GenerateConfig, generate
from afford.sim import camera
from afford.sim.affordance import decode_affordance, encode_affordance
from afford.sim.affordances import Affordance
from afford.sim.scene import ObjectSpec as O


def _generate_cli(out: Path, n: int, workers: int, shard: int = SHARD, **kw) -> subprocess.Popen:
    cmd = [sys.executable, "-m", "afford.cli.main", "generate", "--out", str(out), "--sequences", str(n)]
    cmd += ["--seed", str(SMALL_SEED), "--workers", str(workers), "--shard-size", str(shard), "--json"]
    return subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, **kw)


@pytest.fixture
def small(small_dataset) -> Path:
    return small_dataset


def _same(a: Dataset, b: Dataset, i: int) -> bool:
    x, y = a.sequence(i), b.sequence(i)
    arrays = all(
        np.array_equal(getattr(x, k), getattr(y, k), equal_nan=True)
        for k in ("rgb", "depth", "actions", "held", "poses")
    )
    return (
        arrays
        and len(x.affordances) == len(y.affordances)
        and all(np.array_equal(p, q) for p, q in zip(x.affordances, y.affordances, strict=True))
    )


@pytest.mark.slow
def test_two_workers_give_identical_content(small, tmp_path):
    proc = _generate_cli(tmp_path / "two", N, workers=2)
    out, err = proc.communicate(timeout=300)
    assert proc.returncode == 0, err.decode()
    assert json.loads(out)["shards_made"] == N // SHARD
    a, b = Dataset(small), Dataset(tmp_path / "two")
    assert all(_same(a, b, i) for i in range(N))


@pytest.mark.slow
def test_killed_generate_resumes_to_exactly_n(tmp_path):
    root, n = tmp_path / "killed", 10
    proc = _generate_cli(root, n, workers=1, start_new_session=True)
    first = shard_path(root, 0)
    deadline = time.time() + 120
    while not first.exists() and time.time() < deadline:
        time.sleep(0.05)
    assert first.exists(), "no shard written in time"
    os.killpg(proc.pid, signal.SIGKILL)  # kill -9, mid-run
    proc.wait()
    made_before = len(list((root / "shards").glob("shard-*.npz")))
    assert made_before < n // SHARD, "the run finished before it could be killed"
    proc = _generate_cli(root, n, workers=1)
    out, err = proc.communicate(timeout=300)
    assert proc.returncode == 0, err.decode()
    report = json.loads(out)
    assert report["shards_already_there"] == made_before
    assert report["shards_made"] == n // SHARD - made_before
    problems, good = verify(root)
    assert problems == [] and good == n // SHARD
    ds = Dataset(root)
    assert [s.index for s in ds.sequences()] == list(range(n))  # exactly N, none twice
    assert not list((root / "shards").glob(".*.tmp"))


def test_sequences_hold_consistent_records(small):
    ds = Dataset(small)
    for seq in ds.sequences():
        t = seq.length + 1
        assert seq.rgb.shape == (t, 128, 128, 3) and seq.depth.shape == (t, 128, 128)
        assert seq.poses.shape == (t, len(seq.slots), 7) and len(seq.affordances) == t
        for k, a in enumerate(seq.actions):
            # Every executed affordance was one of the state's ground-truth list (turn filled in).
            listed = [decode_affordance(r) for r in seq.affordances[k]]
            act = decode_affordance(a)
            assert any(b.type == act.type and b.position == act.position for b in listed)
            if act.type == "turn":
                assert act.turn in (90, -90)
            # A grasp leaves something held; a place or turn leaves the gripper empty.
            assert (seq.held[k + 1] >= 0) == (act.type == "grasp")
        image = seq.image(0)
        assert image.shape == (128, 128, 4) and 0 <= image.min() and image.max() <= 1


def test_splits_partition_the_sequences(small):
    ds = Dataset(small)
    all_indices = sorted(i for s in ("train", "val", "test") for i in ds.indices(s))
    assert all_indices == list(range(N))
    with pytest.raises(DataError, match="no split"):
        ds.indices("holdout")


def test_corrupt_shard_is_named_and_others_stay_readable(small, tmp_path):
    import shutil

    root = tmp_path / "copy"
    shutil.copytree(small, root)
    bad = shard_path(root, 1)
    bad.write_bytes(bad.read_bytes()[: bad.stat().st_size // 2])  # truncated
    ds = Dataset(root)
    with pytest.raises(DataError, match="shard-000001"):
        ds.sequence(SHARD)
    assert ds.sequence(0).index == 0 and ds.sequence(2 * SHARD).index == 2 * SHARD
    problems, good = verify(root)
    assert len(problems) == 1 and "shard-000001" in problems[0] and good == N // SHARD - 1
    assert main(["data", "verify", str(root)]) == 1


def test_unknown_format_version_is_refused(small, tmp_path, capsys):
    import shutil

    root = tmp_path / "future"
    shutil.copytree(small, root)
    manifest = json.loads((root / MANIFEST).read_text())
    manifest["version"] = 99
    (root / MANIFEST).write_text(json.dumps(manifest))
    with pytest.raises(DataError, match="format version 99"):
        Dataset(root)
    assert main(["data", "info", str(root)]) == 2
    assert "format version 99" in capsys.readouterr().err


def test_resume_with_other_settings_is_refused(small):
    with pytest.raises(DataError, match="same settings"):
        config = GenerateConfig(sequences=N + 1, seed=SMALL_SEED, workers=1, shard_size=SHARD)
        generate(small, config, progress=False)


def test_info_and_show(small, tmp_path, capsys):
    assert main(["data", "info", str(small), "--json"]) == 0
    info = json.loads(capsys.readouterr().out)
    assert info["sequences_present"] == N and info["format_version"] == 1
    assert sum(info["executions_per_type"].values()) == info["executions"]
    assert sum(info["sequence_length_histogram"].values()) == N
    png = tmp_path / "seq.png"
    assert main(["data", "show", str(small), "--split", "train", "--index", "0", "--out", str(png)]) == 0
    assert png.stat().st_size > 1000
    assert main(["data", "show", str(small), "--split", "train", "--index", "999"]) == 2


def test_encode_decode_roundtrip():
    a = Affordance("turn", (0.1, 0.2, 0.025), 90.0, False, -90)
    b = decode_affordance(encode_affordance(a))
    assert b.type == a.type and b.turn == a.turn and np.allclose(b.position, a.position)


def _marker_image(row: np.ndarray) -> np.ndarray:
    """A blank RGBD image with one bright pixel where `row`'s position projects."""
    image = np.zeros((1, 128, 128, 4), dtype=np.float32)
    r, c = camera.pixel_index(row[0, 1:4])
    image[0, r, c, 0] = 1.0
    return image


@pytest.mark.parametrize("seed", range(5))
def test_augmentation_keeps_rows_on_their_pixels(seed):
    row = encode_affordance(Affordance("grasp", (0.05, 0.3, 0.04), 30.0, False))[None]
    # Put the point at a pixel centre, so a rounding at the border cannot move it.
    centre = camera.pixel_to_world(camera.world_to_pixel(row[0, 1:4]) // 1 + 0.5, camera.depth_to_unit(0.66))
    row[0, 1:3] = centre[:2]
    row[0, 3] = 0.04
    rng = np.random.default_rng(seed)
    config = AugmentConfig(shift_px=4, mirror=True, angle_flip=False)
    images, (moved,) = augment(_marker_image(row), [row], config, rng)
    r, c = camera.pixel_index(moved[0, 1:4])
    assert images[0, r, c, 0] == 1.0
    assert moved[0, 3] == pytest.approx(row[0, 3])
    mirrored = not np.isclose(moved[0, 4], row[0, 4])
    assert (moved[0, 4] - (180 - row[0, 4] if mirrored else row[0, 4])) % 360 == pytest.approx(0)


def test_angle_flip_only_where_angle_is_free():
    rows = np.stack(
        [
            encode_affordance(Affordance("grasp", (0, 0.3, 0.02), 30.0, False)),
            encode_affordance(Affordance("place", (0, 0.3, 0.06), 30.0, True)),
        ]
    )
    flipped = set()
    for seed in range(20):
        _, (out,) = augment(
            np.zeros((1, 128, 128, 4), np.float32),
            [rows],
            AugmentConfig(0, False, True),
            np.random.default_rng(seed),
        )
        assert out[0, 4] == pytest.approx(30.0)
        flipped.add(round(float(out[1, 4])))
    assert flipped == {30, 210}


def test_torch_datasets(small):
    import torch

    from afford.data.torch_data import (
        PredictionData,
        RecognitionData,
        collate_prediction,
        collate_recognition,
    )

    ds = Dataset(small)
    rec = RecognitionData(ds, "train", AugmentConfig())
    images, lists = collate_recognition([rec[0], rec[1]])
    assert images.shape == (2, 4, 128, 128) and images.dtype == torch.float32
    assert lists[0].shape[1] == 7
    pred = PredictionData(ds, "train", augment_config=NO_AUGMENT)
    batch = [pred[k] for k in range(len(pred))]
    images, actions, steps = collate_prediction(batch)
    assert images.shape[1] == int(steps.max()) + 1 and actions.shape[:2] == (len(batch), int(steps.max()))
    assert int(steps.min()) >= 1 and int(steps.max()) <= 4


def test_generate_heals_corrupt_shards_and_info_names_them(small, tmp_path, capsys):
    from afford.data.format import read_manifest

    root = tmp_path / "copy"
    shutil.copytree(small, root)
    truncated, flipped = shard_path(root, 0), shard_path(root, 2)
    truncated.write_bytes(truncated.read_bytes()[:1000])
    data = bytearray(flipped.read_bytes())
    data[len(data) // 2] ^= 0xFF  # one byte inside the images: only the checksum can tell
    flipped.write_bytes(bytes(data))
    original = [seq.index for seq in Dataset(small).sequences()]

    assert main(["data", "info", str(root), "--json"]) == 0
    info = json.loads(capsys.readouterr().out)
    assert len(info["shards"]["corrupt"]) == 1 and "shard-000000" in info["shards"]["corrupt"][0]
    assert info["sequences_present"] == len(original) - SHARD  # the good shards still counted

    m = read_manifest(root)
    assert main(["generate", "--out", str(root), "--sequences", str(m.sequences), "--seed", str(m.seed),
                 "--workers", "1", "--shard-size", str(m.shard_size), "--json"]) == 0  # fmt: skip
    report = json.loads(capsys.readouterr().out)
    remade = " ".join(report["shards_remade"])
    assert report["shards_made"] == 2 and "shard-000000" in remade and "shard-000002" in remade
    problems, good = verify(root)
    assert problems == [] and good == m.n_shards
    a, b = Dataset(small), Dataset(root)
    assert all(_same(a, b, i) for i in range(len(original)))  # made again, identical


def test_continuous_turn_angles_draw_any_angle_and_resume_only_as_made(tmp_path):
    from afford.data.format import DataError, Dataset
    from afford.data.generate import GenerateConfig, generate
    from afford.sim.affordance import Col

    config = GenerateConfig(sequences=8, seed=6, workers=1, shard_size=4, turn_angles="continuous")
    generate(tmp_path / "c", config, progress=False)
    data = Dataset(tmp_path / "c")
    turns = [float(r[Col.TURN]) for i in range(8) for r in data.sequence(i).actions if r[Col.TURN]]
    assert turns and all(-180 <= t <= 180 for t in turns) and any(abs(t) != 90 for t in turns)
    with pytest.raises(DataError, match="continuous turns"):
        generate(tmp_path / "c", GenerateConfig(sequences=8, seed=6, workers=1, shard_size=4), progress=False)


def test_balances_layout_starts_level_with_the_block_far_off_its_support(tmp_path):
    from afford.sim.layout import LAYOUTS, random_layout

    offsets = []
    for i in range(200):
        specs = random_layout(np.random.default_rng([9, i]), LAYOUTS["balances"])
        block = next(s for s in specs if s.kind == "block")
        support = next(s for s in specs if s.kind == "support")  # the first support is the block's
        offsets.append(np.hypot(block.pos[0] - support.pos[0], block.pos[1] - support.pos[1]))
    offsets = np.array(offsets)
    # Beyond 2.5 cm the bare block cannot balance; the default layout never goes past 2 cm.
    assert offsets.max() <= 0.045 + 1e-9 and (offsets > 0.025).mean() > 0.3

    config = GenerateConfig(sequences=8, seed=4, workers=1, shard_size=4, layout="balances")
    generate(tmp_path / "b", config, progress=False)
    data = Dataset(tmp_path / "b")
    assert data.manifest.generator["layout_name"] == "balances"
    level = []
    for i in range(8):
        seq = data.sequence(i)
        w, x, y, _ = seq.poses[0, seq.slots.index("block0"), 3:]
        level.append(1 - 2 * (x * x + y * y))  # the block's up axis, its z component
    assert min(level) >= LAYOUTS["balances"].level_cos
    with pytest.raises(DataError, match="balances layout"):
        generate(tmp_path / "b", GenerateConfig(sequences=8, seed=4, workers=1, shard_size=4), progress=False)


def test_visibility_counts_the_objects_a_mask_hides_and_what_covers_them(scene):
    from afford.data.draws import pose_array
    from afford.data.visibility import Visibility

    # A ball under the block (hidden, covered by the block), a cup beside it (seen), and the
    # same scene with the cup held (not counted).
    scene.reset(
        [O.upright("ball", 0.0, 0.30), O.upright("cup", 0.15, 0.22), O.upright("block", 0.0, 0.30, z=0.05)],
        check=False,
    )
    slots = tuple(name for name, _ in scene.slots)
    masks, poses = np.stack([scene.instance_mask()] * 2), np.stack([pose_array(scene)] * 2)
    held = np.array([-1, slots.index("cup0")])
    seen = Visibility()
    seen.add(masks, poses, held, slots)
    assert seen.present == {"ball": 2, "cup": 1, "block": 2}
    assert seen.hidden == {"ball": 2} and seen.covered_by["ball"] == {"block": 2}
    assert seen.as_dict()["per_kind"]["ball"]["share"] == 1.0
