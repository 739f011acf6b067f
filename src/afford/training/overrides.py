"""`--set KEY=VALUE`: a config field changed from the command line, typed by the field.

KEY is a field's flat name (`lr`) or its path in a grouped config (`training.lr`): see
training/fields.py.
"""

from __future__ import annotations

import typing

from afford.errors import UserError
from afford.training.fields import flat_names, leaf_type, paths, with_fields


class OverrideError(UserError):
    """A --set that names no field of the config, or a value of the wrong type."""


_TRUE, _FALSE = {"1", "true", "yes", "on"}, {"0", "false", "no", "off"}


def _parse(text: str, kind) -> object:
    if kind is bool:
        if text.lower() in _TRUE | _FALSE:
            return text.lower() in _TRUE
        raise ValueError(f"{text!r} is not a boolean (true/false)")
    if typing.get_origin(kind) is tuple:
        item = typing.get_args(kind)[0]
        return tuple(_parse(t.strip(), item) for t in text.split(",") if t.strip())
    return kind(text)


def apply_overrides(config, pairs: list[str] | None):
    """A copy of the frozen dataclass `config` with each "KEY=VALUE" of `pairs` applied."""
    if not pairs:
        return config
    known = paths(type(config))
    changes = {}
    for pair in pairs:
        key, sep, value = pair.partition("=")
        key = key.strip()
        if not sep or key not in known:
            raise OverrideError(
                f"--set {pair!r}: expected KEY=VALUE with KEY one of: {', '.join(flat_names(type(config)))}"
            )
        try:
            changes[key] = _parse(value.strip(), leaf_type(type(config), known[key]))
        except ValueError as e:
            raise OverrideError(f"--set {pair!r}: {e}") from None
    return with_fields(config, **changes)


def preset_config(presets: dict, preset: str, **given):
    """A preset's config with the options the command line gave (None: not given) set."""
    return with_fields(presets[preset], **{k: v for k, v in given.items() if v is not None})
