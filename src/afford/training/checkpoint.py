"""Checkpoints: one safetensors file holding the weights, the optimiser state and the config.

Everything a resumed run or a later evaluation needs is in the file: tensors under
``model.*`` and ``optim.*``, and in the safetensors metadata a JSON record with the net's kind
("recognition" or "prediction"), its config, the training step and the optimiser's
hyper-parameters. Files are written to a temporary name and renamed: a kill never leaves half a
checkpoint.
"""

from __future__ import annotations

import json
import os
from pathlib import Path

import torch
from safetensors import SafetensorError
from safetensors.torch import load_file, save_file
from torch import nn

from afford.errors import UserError
from afford.training.fields import from_dict, merged

FORMAT_VERSION = 1
# A training run's folder keeps its latest checkpoint and its best by validation loss.
LAST, BEST = "last.safetensors", "best.safetensors"


class CheckpointError(UserError):
    """A checkpoint that is missing, corrupt, or of another kind or architecture."""


def save_checkpoint(
    path: str | Path,
    model: nn.Module,
    kind: str,
    config: dict,
    step: int,
    optimizer: torch.optim.Optimizer | None = None,
    extra: dict | None = None,
) -> None:
    tensors = {f"model.{k}": v.detach().cpu().contiguous().clone() for k, v in model.state_dict().items()}
    groups = []
    if optimizer is not None:
        state = optimizer.state_dict()
        for idx, entries in state["state"].items():
            for name, value in entries.items():
                t = value if torch.is_tensor(value) else torch.tensor(value)
                tensors[f"optim.{idx}.{name}"] = t.detach().cpu().contiguous().clone()
        groups = state["param_groups"]
    meta = {
        "format": FORMAT_VERSION,
        "kind": kind,
        "config": config,
        "step": step,
        "param_groups": groups,
        "extra": extra or {},
    }
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp")
    save_file(tensors, str(tmp), metadata={"afford": json.dumps(meta)})
    os.replace(tmp, path)


def read_checkpoint(path: str | Path, kind: str) -> tuple[dict[str, torch.Tensor], dict]:
    """(tensors, metadata) of a checkpoint of `kind`; CheckpointError naming the problem."""
    path = Path(path)
    if not path.is_file():
        raise CheckpointError(f"{path}: no such checkpoint")
    try:
        from safetensors import safe_open

        with safe_open(str(path), framework="pt") as f:
            raw_meta = (f.metadata() or {}).get("afford")
        tensors = load_file(str(path))
    except (SafetensorError, OSError, ValueError) as e:
        raise CheckpointError(f"{path}: not a readable safetensors checkpoint ({e})") from None
    if raw_meta is None:
        raise CheckpointError(f"{path}: a safetensors file, but not an afford checkpoint (no metadata)")
    meta = json.loads(raw_meta)
    if meta.get("kind") != kind:
        raise CheckpointError(f"{path}: a {meta.get('kind')} checkpoint, not a {kind} one")
    return tensors, meta


def load_model_state(model: nn.Module, tensors: dict[str, torch.Tensor], path: str | Path) -> None:
    """Copy `model.*` tensors into `model`; a different architecture is a CheckpointError."""
    state = {k[len("model.") :]: v for k, v in tensors.items() if k.startswith("model.")}
    if hasattr(model, "adapt_state"):  # e.g. a one-hypothesis prediction net into a K-hypothesis one
        state = model.adapt_state(state)
    own = model.state_dict()
    missing = sorted(set(own) - set(state))
    unexpected = sorted(set(state) - set(own))
    wrong = [k for k in own if k in state and own[k].shape != state[k].shape]
    if missing or unexpected or wrong:
        detail = (missing + unexpected + wrong)[:3]
        raise CheckpointError(
            f"{path}: the checkpoint's architecture differs from its config's net ({', '.join(detail)} ...)"
        )
    model.load_state_dict(state)


def load_optimizer_state(
    optimizer: torch.optim.Optimizer, tensors: dict[str, torch.Tensor], meta: dict
) -> None:
    state: dict[int, dict] = {}
    for key, value in tensors.items():
        if key.startswith("optim."):
            _, idx, name = key.split(".", 2)
            state.setdefault(int(idx), {})[name] = value
    if meta.get("param_groups"):
        optimizer.load_state_dict({"state": state, "param_groups": meta["param_groups"]})


def export_weights(
    src: str | Path,
    dst: str | Path,
    kind: str,
    half: bool = True,
    extra: dict | None = None,
    config: dict | None = None,
    beside: dict[str, str] | None = None,
    config_cls: type | None = None,
) -> int:
    """A checkpoint's weights alone (no optimiser state), float16 by default, for shipping.

    Returns the file size in bytes. `extra` is merged into the metadata (e.g. the tuned cut-off),
    `config` into the net's config (values fitted after training, e.g. a head's calibration;
    by field name, so `config_cls`, the config's class, must come with it);
    `beside` adds safetensors metadata keys next to the checkpoint's own (e.g. its recipe).
    """
    tensors, meta = read_checkpoint(src, kind)
    if config:
        if config_cls is None:
            raise TypeError("export_weights: config values need the config's class (config_cls)")
        meta = {**meta, "config": merged(config_cls, meta["config"], config)}
    out = {}
    for k, v in tensors.items():
        if k.startswith("model."):
            out[k] = v.half() if half and v.is_floating_point() else v
    meta = {**meta, "param_groups": [], "extra": {**(extra or {}), "exported_from": str(src)}}
    dst = Path(dst)
    dst.parent.mkdir(parents=True, exist_ok=True)
    save_file(out, str(dst), metadata={**(beside or {}), "afford": json.dumps(meta)})
    return dst.stat().st_size


def load_net_from_checkpoint(
    path: str | Path, kind: str, config_cls, net_cls
) -> tuple[nn.Module, object, dict]:
    """(net in eval mode, its config, metadata) rebuilt from a checkpoint of `kind`.

    The config comes from the checkpoint itself (training/fields.from_dict: flat or grouped, JSON
    lists back to tuples, unknown keys from an older or newer afford ignored), so a net always
    loads with the shape it was trained at.
    """
    tensors, meta = read_checkpoint(path, kind)
    try:
        config = from_dict(config_cls, meta["config"])
        net = net_cls(config)
    except (TypeError, ValueError, KeyError) as e:
        raise CheckpointError(f"{path}: unusable {kind} config ({e})") from None
    load_model_state(net, tensors, path)
    return net.eval(), config, meta
