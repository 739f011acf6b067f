"""Planning over every foreseen outcome (planning/branches.py): branches, their probabilities,
and the expected eq. (5)."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import torch

from afford.planning.branches import Branches, BranchingModel, keep
from afford.planning.goal import Goal
from afford.planning.learned import LearnedModel
from afford.planning.tree import Node
from afford.prediction.config import PRESETS as PRED
from afford.prediction.model import PredictionNet
from afford.recognition.config import PRESETS as REC
from afford.recognition.infer import Recognizer
from afford.recognition.model import RecognitionNet
from afford.sim.affordance import encode_affordance
from afford.sim.affordances import Affordance
from afford.sim.scene import ObjectSpec
from afford.training.fields import with_fields

FORKED = with_fields(PRED["tiny"], hypotheses=2, hypotheses_by="effect", fork="latent")
SPECS = [ObjectSpec.upright("cup", 0.05, 0.3), ObjectSpec.upright("block", -0.05, 0.22)]
GRASP = Affordance("grasp", (0.05, 0.3, 0.0425), 0.0, True)
TURN = Affordance("turn", (-0.05, 0.22, 0.025), 0.0, False, 90)


def _model(scene, config, kind=BranchingModel):
    torch.manual_seed(0)
    recognizer = Recognizer(RecognitionNet(REC["tiny"]), REC["tiny"])
    scene.reset(SPECS)
    return kind(scene.observe(), recognizer, PredictionNet(config))


def test_keep_drops_unlikely_branches_but_never_the_likeliest():
    assert keep(np.array([0.1, 0.6, 0.02, 0.28])).tolist() == [1, 3, 0]
    assert keep(np.array([0.1, 0.6, 0.02, 0.28]), most=2).tolist() == [1, 3]
    assert keep(np.array([0.01, 0.01]), floor=0.5).tolist() == [0]


def test_step_outcomes_are_the_candidates_and_carry_on_as_the_picked_step_does():
    torch.manual_seed(0)
    net = PredictionNet(FORKED).eval()
    image = torch.rand(2, 4, 128, 128)
    rows = torch.from_numpy(np.stack([encode_affordance(GRASP), encode_affordance(TURN)]))
    latent, memory = net.encode(image)
    with torch.no_grad():
        out = net.step_outcomes(latent, memory, image, rows)
        picked = net.step_hypotheses(latent, memory, image, rows)
        picked_latent, picked_memory, picked_image = picked.latent, picked.memory, picked.image
        hyp = picked.hypotheses
    assert out.images.shape == (2, 2, 4, 128, 128) and out.probability.shape == (2, 2)
    assert torch.allclose(out.probability.sum(1), torch.ones(2))
    assert torch.allclose(out.images, hyp.candidates)
    for b in range(2):
        k = int(hyp.picked[b])
        assert torch.allclose(out.latent[b, k], picked_latent[b])
        assert torch.allclose(out.memory[b, k], picked_memory[b])
        assert torch.allclose(out.images[b, k], picked_image[b])


def test_a_one_outcome_net_branches_as_the_learned_model_predicts(scene):
    branching, plain = _model(scene, PRED["tiny"]), _model(scene, PRED["tiny"], LearnedModel)
    goal = Goal(np.full((8, 8, 4), 0.5))
    nodes = []
    for model in (branching, plain):
        image, state = model.root()
        ((child, state),) = model.predict([Node((), image, state)], [TURN])
        nodes.append(Node((TURN,), child, state))
    assert nodes[0].state.probability.tolist() == [1.0]
    assert np.allclose(nodes[0].image, nodes[1].image, atol=1e-6)
    assert np.allclose(branching.score(goal, [nodes[0]]).loss, plain.score(goal, [nodes[1]]).loss)


def test_two_outcomes_split_every_branch_and_score_the_expected_loss(scene):
    model = _model(scene, FORKED)
    image, state = model.root()
    root = Node((), image, state)
    ((image1, state1),) = model.predict([root], [TURN])
    assert 1 <= len(state1.probability) <= 2 and np.isclose(state1.probability.sum(), 1.0)
    assert np.array_equal(image1, state1.images[0])  # the state's picture: the likeliest branch
    children = model.predict([Node((TURN,), image1, state1)] * 2, [GRASP, TURN])
    for _, s in children:
        assert len(s.probability) <= 4 and np.isclose(s.probability.sum(), 1.0)
        assert np.all(np.diff(s.probability) <= 0)  # likeliest first
    goal = Goal(np.full((8, 8, 4), 0.5))
    nodes = [Node((TURN, a), i, s) for a, (i, s) in zip((GRASP, TURN), children, strict=True)]
    by_hand = [s.probability @ goal.loss(s.images) for _, s in children]
    assert np.allclose(model.score(goal, nodes).loss, by_hand)


def test_the_expected_loss_weighs_each_outcome_by_its_probability():
    near, far = np.full((1, 16, 16, 4), 0.5, np.float32), np.zeros((1, 16, 16, 4), np.float32)
    goal = Goal(np.full((4, 4, 4), 0.5))
    empty = torch.zeros(1)

    def node(p_far: float) -> Node:
        images = np.concatenate([near, far])
        branches = Branches(np.array([1 - p_far, p_far]), empty, empty, images)
        return Node((), images[0], branches)

    plain = SimpleNamespace(risk=0.0)  # the score reads only the model's risk
    losses = BranchingModel.score(plain, goal, [node(0.1), node(0.6)]).loss
    assert np.allclose(losses, [0.1 * 0.25, 0.6 * 0.25])  # a far outcome costs by how often it follows
    assert Goal(goal.patch, negative=True).best(losses) == 1 and goal.best(losses) == 0


def test_with_risk_the_plan_the_net_is_sure_of_wins_at_equal_expected_loss():
    goal = Goal(np.full((4, 4, 4), 0.5))
    empty = torch.zeros(1)
    at = {v: np.full((1, 16, 16, 4), v, np.float32) for v in (0.0, 0.25, 0.5)}
    # Both expect a squared error of 0.0625 in the window: one for sure (every pixel 0.25 away),
    # the other at odds of 3 to 1 between the goal itself (0) and an image 0.5 away (0.25).
    sure = Node((), at[0.25][0], Branches(np.ones(1), empty, empty, at[0.25]))
    both = np.concatenate([at[0.5], at[0.0]])
    coin = Node((), both[0], Branches(np.array([0.75, 0.25]), empty, empty, both))
    plain = BranchingModel.score(SimpleNamespace(risk=0.0), goal, [sure, coin])
    assert np.allclose(plain.loss, [0.0625, 0.0625]) and np.allclose(plain.spread, [0.0, np.sqrt(3) * 0.0625])
    averse = BranchingModel.score(SimpleNamespace(risk=1.0), goal, [sure, coin])
    assert goal.best(averse.loss) == 0  # the sure one
    negative = Goal(goal.patch, negative=True)
    assert negative.best(BranchingModel.score(SimpleNamespace(risk=1.0), negative, [sure, coin]).loss) == 0
