"""A config's fields by name, whether the config is flat or groups its fields into records.

Every net's config is a frozen dataclass. A small one is flat (`RecognitionConfig.lr`); a large
one groups its fields into records (`PredictionConfig.training.lr`). Each field has one path
(`training.lr`) and one flat name: its own (`lr`), or, where its name says little outside its
group, the one its record gives it (`loss_l1` for `loss.l1`); no two fields share a name. So
`--set lr=1e-4`, a config stored as one flat dict (the shipped files' form), and a recipe's
command all name the same field.
"""

from __future__ import annotations

import dataclasses
import functools
import typing


def _is_record(kind) -> bool:
    return isinstance(kind, type) and dataclasses.is_dataclass(kind)


@functools.cache
def hints(cls: type) -> dict[str, object]:
    """Each field's type, resolved (the annotations are strings under `from __future__`)."""
    return typing.get_type_hints(cls)


@functools.cache
def groups(cls: type) -> frozenset[str]:
    """The fields of `cls` that are records of fields (none in a flat config)."""
    return frozenset(f.name for f in dataclasses.fields(cls) if _is_record(hints(cls)[f.name]))


@functools.cache
def paths(cls: type) -> dict[str, tuple[str, ...]]:
    """Every name a field of `cls` goes by -> its path, e.g. {"lr": ("training", "lr"), ...}."""
    out: dict[str, tuple[str, ...]] = {}

    def add(name: str, path: tuple[str, ...]) -> None:
        if out.get(name, path) != path:
            raise TypeError(f"{cls.__name__}: two fields go by the name {name!r}")
        out[name] = path

    for f in dataclasses.fields(cls):
        kind = hints(cls)[f.name]
        if f.name not in groups(cls):
            add(f.name, (f.name,))
            continue
        # A field whose name reads only beside its group's (`loss.l1`) has its flat name in
        # the record's `flat_names` (`loss_l1`); any other goes by its own.
        renamed = getattr(kind, "flat_names", {})
        if stray := set(renamed) - {g.name for g in dataclasses.fields(kind)}:
            raise TypeError(f"{kind.__name__}.flat_names names no field: {sorted(stray)}")
        for g in dataclasses.fields(kind):
            add(f"{f.name}.{g.name}", (f.name, g.name))
            add(renamed.get(g.name, g.name), (f.name, g.name))
    if clash := [name for name in out if name in groups(cls)]:
        raise TypeError(f"{cls.__name__}: a field goes by the name of the group {clash[0]!r}")
    return out


def leaf_type(cls: type, path: tuple[str, ...]):
    """The type of the field at `path`."""
    for name in path[:-1]:
        cls = hints(cls)[name]
    return hints(cls)[path[-1]]


def flat_names(cls: type) -> list[str]:
    """Each field's flat name (`lr`, `loss_l1`), as `--set` and stored flat configs write them."""
    return sorted(name for name in paths(cls) if "." not in name)


def flat(config) -> dict[str, object]:
    """The config's fields as one flat dict, each under its path joined by '.' (`training.lr`)."""
    out: dict[str, object] = {}
    for f in dataclasses.fields(config):
        value = getattr(config, f.name)
        if dataclasses.is_dataclass(value):
            out.update({f"{f.name}.{k}": v for k, v in flat(value).items()})
        else:
            out[f.name] = value
    return out


def with_fields(config, **changes):
    """A copy of `config` with the fields named (by any of their names) set; a field named
    twice (`lr` and `training.lr`) takes the later value, as a repeated `--set` does."""
    known = paths(type(config))
    by_group: dict[str, dict[str, object]] = {}
    top: dict[str, object] = {}
    for name, value in changes.items():
        if name not in known:
            raise TypeError(f"{type(config).__name__} has no field {name!r}")
        path = known[name]
        if len(path) == 1:
            top[path[0]] = value
        else:
            by_group.setdefault(path[0], {})[path[1]] = value
    for group, values in by_group.items():
        top[group] = dataclasses.replace(getattr(config, group), **values)
    return dataclasses.replace(config, **top)


def _value(value):
    return tuple(value) if isinstance(value, list) else value


def from_dict(cls: type, stored: dict):
    """A `cls` from a stored dict: grouped ({"training": {"lr": ...}}) or flat ({"lr": ...},
    as the shipped files store them); a group's entries first, then flat names. Unknown keys,
    from an older or newer afford, are ignored, but for the fields `cls.removed` names: a stored
    value other than the one this code runs raises ValueError, since the net it describes would
    load with parts missing or train another way. JSON lists come back as tuples."""
    known, records = paths(cls), groups(cls)
    check_removed(cls, stored)
    changes: dict[str, object] = {}
    for key, value in stored.items():
        if key in records and isinstance(value, dict):
            changes.update({f"{key}.{k}": _value(v) for k, v in value.items() if f"{key}.{k}" in known})
    for key, value in stored.items():
        if key not in records and key in known:
            changes[".".join(known[key])] = _value(value)
    return with_fields(cls(), **changes)


def check_removed(cls: type, stored: dict) -> None:
    """ValueError where a stored config sets a field `cls.removed` names (flat, or in a group
    under its own name or its flat one) to other than the one value this code runs."""
    removed = getattr(cls, "removed", {})
    entries = list(stored.items())
    for group, values in stored.items():
        if group in groups(cls) and isinstance(values, dict):
            entries += [(k, v) for k, v in values.items()] + [(f"{group}_{k}", v) for k, v in values.items()]
    for key, value in entries:
        if key in removed and _value(value) != removed[key]:
            raise ValueError(
                f"{key}={value!r} asks for a feature this afford does not hold (it runs "
                f"{key}={removed[key]!r}); the experiment pages name the commit that has it"
            )


def merged(cls: type, stored: dict, changes: dict) -> dict:
    """A stored config dict of a `cls` with `changes` (by any of their names) written in: into
    the field's group where the stored config is grouped, under its flat name where it is flat."""
    known = paths(cls)
    flat_name = {path: name for name, path in known.items() if "." not in name}
    out = {k: dict(v) if isinstance(v, dict) else v for k, v in stored.items()}
    for name, value in changes.items():
        if name not in known:
            raise TypeError(f"{cls.__name__} has no field {name!r}")
        path = known[name]
        if len(path) == 2 and isinstance(out.get(path[0]), dict):
            out[path[0]][path[1]] = value
        else:
            out[flat_name[path]] = value
    return out
