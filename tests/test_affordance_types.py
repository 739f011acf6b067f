"""A fourth affordance type is its own module plus the registry: a toy "poke" (hover over a cup
and come back) registered here goes through detection, execution, the data rows, the symbolic
planner, pictures, and both nets, with no other code touched."""

from dataclasses import replace

import numpy as np
import pytest
import torch
from PIL import Image

from afford.planning.symbolic import CanonicalWorld
from afford.prediction.config import PRESETS as PRED
from afford.prediction.model import PredictionNet
from afford.recognition.config import PRESETS as REC
from afford.recognition.model import RecognitionNet
from afford.recognition.targets import build_targets, loss
from afford.sim.affordance import decode_affordance, encode_affordance
from afford.sim.affordance_types import REGISTRY, AffordanceType, type_index
from afford.sim.affordances import Affordance, parametrise
from afford.sim.scene import ObjectSpec
from afford.training.fields import with_fields
from afford.viz.draw import draw_affordances

HOVER = 0.08  # metres above the cup's centre


def _find(scene, obj, consider, held_kind):
    if obj.kind == "cup":
        consider("poke", obj.pos, obj.pos + np.array([0.0, 0.0, HOVER]), [0.0], True)


POKE = AffordanceType(
    "poke",
    holding=False,
    find=_find,
    act=lambda scene, arm, aff, tcp, q_at: "",  # hover there, touch nothing
    canonical=lambda world, state, aff: state,  # canonically nothing changes
    tcp_above=lambda scene: HOVER,
    colour=(255, 160, 0),
)


@pytest.fixture
def poke(monkeypatch):
    monkeypatch.setitem(REGISTRY, "poke", POKE)
    return POKE


def test_a_registered_type_is_detected_executed_stored_planned_and_drawn(scene, poke):
    specs = [ObjectSpec.upright("cup", 0.05, 0.3), ObjectSpec.upright("block", -0.05, 0.2)]
    scene.reset(specs)
    pokes = [a for a in parametrise(scene.affordances()) if a.type == "poke"]
    assert len(pokes) == 1 and np.allclose(pokes[0].position, scene.object("cup0").pos)
    row = encode_affordance(pokes[0])
    back = decode_affordance(row)  # float32 rows: the same to a micrometre
    assert row[0] == type_index("poke") == 3 and back.type == "poke"
    assert np.allclose(back.position, pokes[0].position, atol=1e-6) and back.symmetric
    before = scene.object("cup0").pos.copy()
    result = scene.execute(pokes[0])
    assert result.executed and result.held is None
    assert np.linalg.norm(scene.object("cup0").pos - before) < 1e-3  # hovered, touched nothing
    world = CanonicalWorld(scene, specs, ["cup0", "block0"])
    assert world.apply(world.start, pokes[0]) == world.start
    picture = draw_affordances(Image.new("RGB", (512, 512)), pokes)
    assert (255, 160, 0) in {picture.getpixel((x, y)) for x in range(512) for y in range(0, 512, 2)}


def test_the_nets_take_a_registered_type_from_their_config(poke):
    types = tuple(REGISTRY)
    torch.manual_seed(0)
    rec = replace(REC["tiny"], types=types)
    raw = RecognitionNet(rec)(torch.rand(1, 4, 128, 128))
    rows = encode_affordance(Affordance("poke", (0.05, 0.3, 0.0425), 0.0, True))[None]
    total, _ = loss(raw, build_targets([rows], rec), rec)
    total.backward()  # a type logit and regression of its own
    pred = with_fields(PRED["tiny"], types=types)
    net = PredictionNet(pred)
    assert len(net.modules_by_type) == 4  # one P^a per type (paper II.C)
    image = torch.rand(1, 4, 128, 128)
    latent, memory = net.encode(image)
    _, _, out = net.step(latent, memory, image, torch.from_numpy(rows))
    assert out.shape == image.shape
