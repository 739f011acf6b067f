"""grad_clip: one wild batch moves the weights by no more than the clip allows."""

import torch
from torch import nn

from afford.prediction.config import PRESETS
from afford.training.fields import with_fields
from afford.training.loop import Loop, _Run


def _moved(tmp_path, clip: float) -> float:
    model = nn.Linear(1, 1, bias=False)
    nn.init.zeros_(model.weight)
    loop = Loop(
        kind="prediction",
        config=with_fields(PRESETS["tiny"], lr=1.0, grad_clip=clip),
        model=model,
        optimizer=torch.optim.SGD(model.parameters(), lr=1.0),
        batches=[torch.ones(1, 1)],
        train_step=lambda x: (1e6 * model(x).sum(), {}),
        validate=lambda: {"loss": 0.0},
    )
    _Run(loop, tmp_path / f"clip{clip}").step(torch.ones(1, 1))
    return float(model.weight.detach().abs().max())


def test_a_wild_batch_is_clipped_only_when_asked(tmp_path):
    assert _moved(tmp_path, 0.0) == 1e6
    assert abs(_moved(tmp_path, 0.5) - 0.5) < 1e-6
