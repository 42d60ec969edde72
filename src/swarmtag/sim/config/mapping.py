"""Scenarios to and from plain mappings and TOML files, with overrides.

The mapping mirrors the dataclasses: top-level keys (``robots``,
``carriers``, ``ticks``, ``tick``, ``detection_radius``, ``perception``,
``time_unit``), one table per part (``[arena]``, ``[bodies]``, ``[motion]``,
``[walk]``, ``[radio]``, ``[camera]``, ``[timing]``, ``[urgency]``,
``[realism]``, and ``[warehouse]``, absent unless given) and an array of
tables ``[[reprioritisations]]``. Overrides are merged on top (nested
tables or dotted keys such as ``"arena.size"``); parts not given take the
defaults, the arena scaled for the carrier count.
Unknown keys are errors that name the key and list the known ones.
"""

from __future__ import annotations

import os
from collections.abc import Iterable, Mapping
from dataclasses import asdict, fields
from typing import Any, Final

from swarmtag._checks import check_int
from swarmtag._toml import read_toml
from swarmtag.errors import ConfigError
from swarmtag.sim.config.parts import (
    LAB_CARRIERS,
    Arena,
    Bodies,
    Motion,
    Realism,
    Reprioritisation,
    Timing,
    UrgencyModel,
    Walk,
)
from swarmtag.sim.config.sensors import Camera, Radio
from swarmtag.sim.config.warehouse import Warehouse

__all__ = ["flat_keys", "load_toml", "merge_layers", "scenario_fields", "scenario_to_mapping"]

_PARTS: Final[dict[str, type[Any]]] = {
    "arena": Arena,
    "bodies": Bodies,
    "motion": Motion,
    "walk": Walk,
    "radio": Radio,
    "camera": Camera,
    "timing": Timing,
    "urgency": UrgencyModel,
    "realism": Realism,
    "warehouse": Warehouse,
}
_OPTIONAL_PARTS: Final = ("warehouse",)
"""Parts that are absent (None) unless the mapping has their table."""
_SCALARS: Final = (
    "robots",
    "carriers",
    "ticks",
    "tick",
    "detection_radius",
    "perception",
    "time_unit",
    "arena_scaling",
    "perception_scaling",
)
_EVENTS: Final = "reprioritisations"


def _known(names: Iterable[str]) -> str:
    return ", ".join(sorted(names))


def _merge(base: dict[str, Any], extra: Mapping[str, Any], where: str) -> dict[str, Any]:
    """``base`` with ``extra`` merged in: tables merge key by key, dotted keys nest."""
    merged = dict(base)
    for key, given in extra.items():
        name: object = key  # keys come from files and scripts
        if not isinstance(name, str):
            msg = f"{where}{name!r}: keys must be strings"
            raise ConfigError(msg)
        head, dot, tail = name.partition(".")
        value = {tail: given} if dot else given
        if isinstance(value, Mapping) and isinstance(merged.get(head), Mapping):
            merged[head] = _merge(dict(merged[head]), value, f"{where}{head}.")
        elif isinstance(value, Mapping):
            merged[head] = _merge({}, value, f"{where}{head}.")
        else:
            merged[head] = value
    return merged


def flat_keys(mapping: Mapping[str, Any], prefix: str = "") -> dict[str, Any]:
    """Nested tables and dotted keys alike as dotted keys.

    >>> flat_keys({"tick": 0.1, "camera": {"range": 1.5}, "timing.dock": 2.0})
    {'tick': 0.1, 'camera.range': 1.5, 'timing.dock': 2.0}
    """
    flat: dict[str, Any] = {}
    for key, value in mapping.items():
        if isinstance(value, Mapping):
            flat.update(flat_keys(value, f"{prefix}{key}."))
        else:
            flat[f"{prefix}{key}"] = value
    return flat


def merge_layers(*layers: Mapping[str, Any]) -> dict[str, Any]:
    """Mappings merged in order, later ones winning (tables key by key, dotted keys nest).

    >>> merge_layers({"camera": {"range": 1.0, "memory": 5.0}}, {"camera.range": 2.0})
    {'camera': {'range': 2.0, 'memory': 5.0}}
    """
    merged: dict[str, Any] = {}
    for layer in layers:
        merged = _merge(merged, layer, "")
    return merged


def _part(name: str, kind: type[Any], given: object, defaults: dict[str, Any]) -> object:
    if not isinstance(given, Mapping):
        msg = f"{name}: {given!r} is not a table of keys ({_known(f.name for f in fields(kind))})"
        raise ConfigError(msg)
    allowed = {f.name for f in fields(kind)}
    for key in given:
        if key not in allowed:
            msg = f"{name}.{key}: unknown key; [{name}] has keys {_known(allowed)}"
            raise ConfigError(msg)
    return kind(**{**defaults, **given})


def _events(given: object) -> tuple[Reprioritisation, ...]:
    if not isinstance(given, list | tuple):
        msg = f"{_EVENTS}: {given!r} is not a list of tables with keys carrier, tick, urgency"
        raise ConfigError(msg)
    events = []
    required = {f.name for f in fields(Reprioritisation)}
    for number, item in enumerate(given, start=1):
        if isinstance(item, Reprioritisation):
            events.append(item)
            continue
        if not isinstance(item, Mapping):
            msg = f"{_EVENTS}[{number}]: {item!r} is not a table with keys carrier, tick, urgency"
            raise ConfigError(msg)
        unknown = set(item) - required
        if unknown:
            msg = f"{_EVENTS}[{number}].{min(unknown)}: unknown key; use {_known(required)}"
            raise ConfigError(msg)
        missing = required - set(item)
        if missing:
            msg = f"{_EVENTS}[{number}]: lacks {_known(missing)}"
            raise ConfigError(msg)
        events.append(Reprioritisation(**item))
    return tuple(events)


def scenario_fields(
    data: Mapping[str, Any], overrides: Mapping[str, Any] | None = None
) -> dict[str, Any]:
    """Keyword arguments for ``Scenario`` from a mapping and optional overrides."""
    checked: object = data  # mappings come from files and scripts
    if not isinstance(checked, Mapping):
        msg = f"scenario: {checked!r} is not a mapping of keys"
        raise ConfigError(msg)
    merged = _merge(_merge({}, data, ""), overrides or {}, "")
    allowed = {*_SCALARS, *_PARTS, _EVENTS}
    for key in merged:
        if key not in allowed:
            msg = f"{key}: unknown key; a scenario has keys {_known(allowed)}"
            raise ConfigError(msg)
    kwargs: dict[str, Any] = {name: merged[name] for name in _SCALARS if name in merged}
    carriers = check_int("carriers", merged.get("carriers", LAB_CARRIERS), low=1)
    for name, kind in _PARTS.items():
        if name in merged:
            scaling = merged.get("arena_scaling", 0.5)
            exponent = float(scaling) if isinstance(scaling, int | float) else 0.5
            defaults = asdict(Arena.scaled(carriers, exponent)) if kind is Arena else asdict(kind())
            kwargs[name] = _part(name, kind, merged[name], defaults)
    if _EVENTS in merged:
        kwargs[_EVENTS] = _events(merged[_EVENTS])
    return kwargs


def load_toml(path: str | os.PathLike[str]) -> dict[str, Any]:
    """The table of a TOML file; unreadable files and syntax errors are ``ConfigError``."""
    return read_toml(path, what="scenario file", error=ConfigError)


def scenario_to_mapping(values: Mapping[str, Any]) -> dict[str, Any]:
    """Plain nested values (tables as dicts, events as a list of dicts), TOML/JSON-ready."""
    result: dict[str, Any] = {}
    for name in _SCALARS:
        result[name] = values[name]
    for name in _PARTS:
        if values[name] is not None or name not in _OPTIONAL_PARTS:
            result[name] = asdict(values[name])
    result[_EVENTS] = [asdict(event) for event in values[_EVENTS]]
    return result
