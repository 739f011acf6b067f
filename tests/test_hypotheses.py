"""Several outcomes per step (PredictionConfig.outcomes.hypotheses): winner-takes-all and the choice head."""

import numpy as np
import pytest
import torch

from afford.prediction.config import PRESETS
from afford.prediction.model import PredictionNet
from afford.prediction.train import sequence_loss
from afford.sim import camera
from afford.sim.affordance import encode_affordance
from afford.sim.affordances import Affordance
from afford.training.checkpoint import load_model_state
from afford.training.fields import with_fields

TINY = PRESETS["tiny"]
PLACE = Affordance("place", (0.1, 0.3, 0.06), 0, True)


def place_rows(n: int) -> torch.Tensor:
    return torch.from_numpy(np.stack([[encode_affordance(PLACE)]] * n))


def two_outcomes(n: int) -> torch.Tensor:
    """The same start and action; half the runs end bright where the place acts, half dark:
    an outcome that one image can only blur."""
    images = torch.full((n, 2, 4, 128, 128), 0.5)
    r, c = camera.pixel_index(np.array(PLACE.position))
    images[: n // 2, 1, :, r - 10 : r + 10, c - 10 : c + 10] = 0.95
    images[n // 2 :, 1, :, r - 10 : r + 10, c - 10 : c + 10] = 0.05
    return images


def test_shapes_and_the_pick_follows_the_truth_or_the_choice_head():
    torch.manual_seed(0)
    net = PredictionNet(with_fields(TINY, hypotheses=3))
    images = two_outcomes(4)
    rolled = net(images[:, 0], place_rows(4), None, images[:, 1:])
    states, candidates, logits, picks = rolled.states, rolled.candidates, rolled.logits, rolled.picks
    assert candidates.shape == (4, 1, 3, 4, 128, 128) and logits.shape == (4, 1, 3) and picks.shape == (4, 1)
    for b in range(4):
        assert torch.equal(states[b, 0], candidates[b, 0, picks[b, 0]])
    free = net.rollout_hypotheses(images[:, 0], place_rows(4))
    assert torch.equal(free.picks, free.logits.argmax(-1))  # planning: the most likely
    with pytest.raises(ValueError, match="hypotheses"):
        PredictionNet(with_fields(PRESETS["tiny-dense"], hypotheses=2))


def test_effect_labels_pick_the_candidate_and_teach_the_head():
    torch.manual_seed(0)
    config = with_fields(TINY, hypotheses=2, hypotheses_by="effect")
    net = PredictionNet(config)
    images = two_outcomes(4)
    labels = torch.tensor([[True], [False], [False], [True]])
    rolled = net(images[:, 0], place_rows(4), None, images[:, 1:], labels)
    picks = rolled.picks
    assert picks[:, 0].tolist() == [1, 0, 0, 1]  # the labels, not the winners
    # Three of the four alike runs labelled: with two and two the head's gradient is zero
    # exactly (same features, the labels' pulls cancel), and only float noise moved it.
    effects = torch.zeros((4, 1, 128, 128), dtype=torch.bool)
    effects[0, 0, :3, :3] = effects[1, 0, :3, :3] = effects[3, 0, :3, :3] = True
    loss = sequence_loss(net, images, place_rows(4), torch.ones(4, dtype=torch.long), effects)
    loss.backward()
    assert net.decoder.choice.weight.grad.abs().sum() > 0  # the head learns the labels
    with pytest.raises(ValueError, match="hypotheses=2"):
        PredictionNet(with_fields(TINY, hypotheses=3, hypotheses_by="effect"))
    # In use the side-effect outcome is carried on where the head gives it more than the cut-off.
    with torch.no_grad():
        for cut, expected in ((0.0, 1), (1.0, 0)):
            net.config = with_fields(config, effect_threshold=cut)
            assert net.rollout_hypotheses(images[:, 0], place_rows(4)).picks.eq(expected).all()


def test_the_winner_is_the_candidate_nearest_the_truth_where_it_changed():
    from afford.prediction.model import winners

    image = torch.full((1, 4, 8, 8), 0.5)
    truth = image.clone()
    truth[:, :, :2, :2] = 1.0  # what the step changed
    right_there = truth.clone()
    right_there[:, :, 4:, :] = 0.4  # off by 0.1 over half the image that did not change
    wrong_there = image.clone()  # the rest exact, the change missed
    candidates = torch.stack([wrong_there, right_there], 1)
    differences = torch.cat([candidates, torch.ones(1, 2, 1, 8, 8)], 2)
    assert winners(candidates, differences, image, truth).tolist() == [1]
    nothing = winners(candidates, differences, image, image)  # no change: the whole image decides
    assert nothing.tolist() == [0]


@pytest.mark.slow
def test_two_hypotheses_draw_both_outcomes_where_one_image_blurs():
    """Trained on an outcome that goes either way, one image learns the grey in between; two
    candidates learn bright and dark, and the choice head splits its belief."""
    images, rows = two_outcomes(4), place_rows(4)
    r, c = camera.pixel_index(np.array(PLACE.position))
    spots = {}
    for k in (1, 2):
        torch.manual_seed(0)
        net = PredictionNet(with_fields(TINY, hypotheses=k))
        opt = torch.optim.Adam(net.parameters(), lr=3e-3)
        for _ in range(200):
            loss = sequence_loss(net, images, rows, torch.ones(4, dtype=torch.long))
            opt.zero_grad()
            loss.backward()
            opt.step()
        with torch.no_grad():
            out = net.rollout_hypotheses(images[:, 0], rows)
        if k == 1:
            spots[k] = out.states[:, 0, :3, r - 5 : r + 5, c - 5 : c + 5].mean()
        else:
            spots[k] = out.candidates[0, 0, :, :3, r - 5 : r + 5, c - 5 : c + 5].mean((1, 2, 3))
            probabilities = out.logits[0, 0].softmax(-1)
    assert 0.3 < spots[1] < 0.7  # one image: between the two, neither
    assert spots[2].max() > 0.75 and spots[2].min() < 0.25  # two: each outcome
    assert probabilities.min() > 0.2  # and the belief is split, as the data is


def test_a_one_hypothesis_checkpoint_loads_into_k_and_predicts_the_same_at_first():
    torch.manual_seed(0)
    one = PredictionNet(TINY)
    tensors = {f"model.{k}": v for k, v in one.state_dict().items()}
    many = PredictionNet(with_fields(TINY, hypotheses=2))
    load_model_state(many, tensors, "one.safetensors")
    images = two_outcomes(2)
    with torch.no_grad():
        a = one.rollout(images[:, 0], place_rows(2))
        b = many.rollout(images[:, 0], place_rows(2))  # uniform choice: the first candidate, the copy
    assert torch.allclose(a, b, atol=1e-6)


def test_forked_in_the_latent_each_candidate_has_its_own_dc_and_the_first_is_the_one_net():
    """fork=latent: a one-hypothesis checkpoint loads, the first candidate is that net's
    prediction exactly (its own P^a end), the others start near it from their own copies;
    the effect label's candidate is the one whose fork learns."""
    torch.manual_seed(0)
    one = PredictionNet(TINY)
    tensors = {f"model.{k}": v for k, v in one.state_dict().items()}
    config = with_fields(TINY, hypotheses=2, hypotheses_by="effect", fork="latent")
    many = PredictionNet(config)
    load_model_state(many, tensors, "one.safetensors")
    images, rows = two_outcomes(2), place_rows(2)
    with torch.no_grad():
        a = one.rollout(images[:, 0], rows)
        rolled = many.rollout_hypotheses(images[:, 0], rows)
        candidates, logits = rolled.candidates, rolled.logits
    assert candidates.shape == (2, 1, 2, 4, 128, 128) and logits.shape == (2, 1, 2)
    assert torch.allclose(a[:, 0], candidates[:, 0, 0], atol=1e-6)
    assert 0 < (candidates[:, 0, 1] - candidates[:, 0, 0]).abs().max() < 0.1
    effects = torch.zeros((2, 1, 128, 128), dtype=torch.bool)
    effects[1, 0, :3, :3] = True  # the second run had a side effect: the second candidate's
    loss = sequence_loss(many, images, rows, torch.ones(2, dtype=torch.long), effects)
    loss.backward()
    place = many.modules_by_type[1]
    assert place.forks[0].out.weight.grad.abs().sum() > 0
    with pytest.raises(ValueError, match="fork"):
        PredictionNet(with_fields(TINY, hypotheses=2, fork="encoder"))


def _moved_by_training(net: PredictionNet, config) -> set[str]:
    """The weights that three training steps (the second and third of three alike runs with a
    side effect: one and one would pull a uniform head equally both ways) change."""
    from afford.prediction.train import make_optimizer

    before = {k: v.clone() for k, v in net.state_dict().items()}
    opt = make_optimizer(net, config)
    images, rows = two_outcomes(3), place_rows(3)
    effects = torch.zeros((3, 1, 128, 128), dtype=torch.bool)
    effects[1:, 0, :3, :3] = True
    for _ in range(3):
        loss = sequence_loss(net, images, rows, torch.ones(3, dtype=torch.long), effects)
        opt.zero_grad()
        loss.backward()
        opt.step()
    return {k for k, v in net.state_dict().items() if not torch.equal(v, before[k])}


def test_training_only_the_other_outcomes_keeps_the_first_exactly():
    from afford.prediction.train import make_optimizer

    torch.manual_seed(0)
    config = with_fields(TINY, hypotheses=2, hypotheses_by="effect", fork="latent", trained="outcomes")
    net = PredictionNet(config)
    moved = _moved_by_training(net, config)
    assert moved and all(".forks." in k or k.startswith("decoder.choice") for k in moved)
    with pytest.raises(ValueError, match="nothing to train"):
        make_optimizer(
            PredictionNet(with_fields(TINY, trained="outcomes")), with_fields(TINY, trained="outcomes")
        )


def test_training_only_the_side_effect_outcome_keeps_the_head_and_the_first_outcome():
    torch.manual_seed(0)
    config = with_fields(TINY, hypotheses=2, hypotheses_by="effect", fork="latent", trained="side")
    net = PredictionNet(config)
    moved = _moved_by_training(net, config)
    assert moved and all(".forks." in k for k in moved)


def test_a_head_on_the_grid_replaces_a_pooled_one_and_alone_learns():
    """choice_head=grid: a two-outcome checkpoint with the pooled head loads with the new head
    as initialised (uniform) and every outcome as it was; trained=head moves the head alone."""
    torch.manual_seed(0)
    pooled = with_fields(TINY, hypotheses=2, hypotheses_by="effect", fork="latent")
    old = PredictionNet(pooled)
    tensors = {f"model.{k}": v for k, v in old.state_dict().items()}
    config = with_fields(pooled, choice_head="grid", choice_channels=4, trained="head")
    net = PredictionNet(config)
    load_model_state(net, tensors, "pooled.safetensors")
    images, rows = two_outcomes(2), place_rows(2)
    with torch.no_grad():
        a = old.rollout_hypotheses(images[:, 0], rows).candidates
        rolled = net.rollout_hypotheses(images[:, 0], rows)
        b, logits = rolled.candidates, rolled.logits
    assert torch.equal(a, b) and torch.equal(logits, torch.zeros_like(logits))
    moved = _moved_by_training(net, config)
    assert moved and all(k.startswith("decoder.choice") for k in moved)
    assert any(k.startswith("decoder.choice_grid") for k in moved)


def test_deeper_forks_load_a_shallow_two_outcome_net_and_draw_the_same_at_first():
    """fork_blocks=2: a two-outcome checkpoint with one forked block loads, both outcomes
    predict exactly as before (the new block a copy of the trunk's), and trained=side moves
    the new block with the rest of the fork, never the trunk."""
    torch.manual_seed(0)
    shallow = with_fields(TINY, p_blocks=2, hypotheses=2, hypotheses_by="effect", fork="latent")
    old = PredictionNet(shallow)
    tensors = {f"model.{k}": v for k, v in old.state_dict().items()}
    deep = with_fields(shallow, fork_blocks=2, trained="side")
    net = PredictionNet(deep)
    load_model_state(net, tensors, "shallow.safetensors")
    images, rows = two_outcomes(2), place_rows(2)
    with torch.no_grad():
        a = old.rollout_hypotheses(images[:, 0], rows).candidates
        b = net.rollout_hypotheses(images[:, 0], rows).candidates
    assert torch.allclose(a, b, atol=1e-6)
    moved = _moved_by_training(net, deep)
    assert any(".forks.0.before.0." in k for k in moved) and all(".forks." in k for k in moved)
    with pytest.raises(ValueError, match="fork_blocks"):
        PredictionNet(with_fields(shallow, fork_blocks=3))
