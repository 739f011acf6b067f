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
