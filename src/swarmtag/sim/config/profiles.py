"""Profiles (SPEC §4.6): named scenario presets holding the simulator's free parameters.

A profile is a TOML file in the scenario layout (``Scenario.from_mapping``)
plus a ``[profile]`` table that names and describes it and, when
``swarmtag calibrate`` wrote it, records how it was fitted::

    [profile]
    name = "paper-sim"
    description = "..."
    [profile.calibration]        # written by swarmtag calibrate (optional)
    baseline = "targets/paper-sim.toml"
    ...

    tick = 0.04
    perception = "split"
    [camera]
    range = 1.5

Shipped profiles live in ``presets/`` and are registered in ``PROFILES``
(a test keeps the two in step): ``paper-sim`` (the default of
``swarmtag simulate`` and of the simulation studies), ``lab`` (the
physical-style study, logs in seconds) and ``base`` (the simulator before
profiles, so that earlier results can be reproduced). Explicit settings
always win over a profile: ``profile.scenario(overrides)`` merges them on top.
"""

from __future__ import annotations

import os
from collections.abc import Mapping
from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path
from types import MappingProxyType
from typing import Any, Final

from swarmtag._inputs import is_regular_file
from swarmtag._toml import read_toml
from swarmtag.errors import ConfigError
from swarmtag.sim.config.mapping import merge_layers, scenario_fields
from swarmtag.sim.config.scenario import Scenario

__all__ = [
    "DEFAULT_PROFILE",
    "PROFILES",
    "Profile",
    "load_profile",
    "profile_path",
    "read_profile_file",
    "write_profile_file",
]

PROFILES: Final = MappingProxyType(
    {
        "paper-sim": "paper-sim.toml",
        "lab": "lab.toml",
        "base": "base.toml",
    }
)
"""Shipped profiles: name -> file in ``presets/``."""
DEFAULT_PROFILE: Final = "paper-sim"
"""The profile of ``swarmtag simulate`` and the simulation studies when none is named."""
_META: Final = "profile"


@dataclass(frozen=True)
class Profile:
    """A named set of scenario values (a partial scenario mapping) and where it came from.

    ``values`` holds only what the profile sets; everything else keeps the
    ``Scenario`` field defaults. ``calibration`` is the record
    ``swarmtag calibrate`` leaves in a profile it wrote (empty otherwise).
    """

    name: str
    description: str = ""
    values: Mapping[str, Any] = field(default_factory=dict)
    calibration: Mapping[str, Any] = field(default_factory=dict)
    source: str | None = None

    def __post_init__(self) -> None:
        scenario_fields(self.values)  # unknown keys and bad tables fail here, naming the key
        Scenario.from_mapping(self.values)  # and so do bad values

    def scenario(self, *layers: Mapping[str, Any]) -> Scenario:
        """The profile's scenario with ``layers`` (nested or dotted keys) merged on top in order.

        >>> load_profile("base").scenario({"carriers": 20}, {"camera.range": 2.0}).camera.range
        2.0
        """
        return Scenario.from_mapping(merge_layers(self.values, *layers))

    def to_mapping(self) -> dict[str, Any]:
        """The TOML layout: the ``[profile]`` table, then the scenario values."""
        meta: dict[str, Any] = {"name": self.name, "description": self.description}
        if self.calibration:
            meta["calibration"] = dict(self.calibration)
        return {_META: meta, **dict(self.values)}

    @classmethod
    def from_mapping(cls, data: Mapping[str, Any], *, source: str | None = None) -> Profile:
        """A profile from its TOML layout; errors name ``source`` and the bad key."""
        prefix = f"{source}: " if source else ""
        meta = data.get(_META)
        if not isinstance(meta, Mapping) or not isinstance(meta.get("name"), str):
            msg = f'{prefix}[profile] with name = "..." is missing'
            raise ConfigError(msg)
        unknown = set(meta) - {"name", "description", "calibration"}
        if unknown:
            msg = f"{prefix}profile.{min(unknown)}: unknown key; [profile] has keys "
            msg += "calibration, description, name"
            raise ConfigError(msg)
        calibration = meta.get("calibration", {})
        if not isinstance(calibration, Mapping):
            msg = f"{prefix}profile.calibration: {calibration!r} is not a table"
            raise ConfigError(msg)
        values = {key: value for key, value in data.items() if key != _META}
        try:
            return cls(
                name=meta["name"],
                description=str(meta.get("description", "")),
                values=values,
                calibration=dict(calibration),
                source=source,
            )
        except ConfigError as error:
            raise ConfigError(f"{prefix}{error}") from None


def profile_path(name: str) -> Path:
    """The file of the shipped profile ``name``; ``ConfigError`` listing the names otherwise."""
    if name not in PROFILES:
        msg = f"profile {name!r}: no such shipped profile (shipped: {', '.join(PROFILES)})"
        raise ConfigError(msg)
    return Path(str(resources.files("swarmtag.sim.config") / "presets" / PROFILES[name]))


def read_profile_file(path: str | os.PathLike[str]) -> Profile:
    """Read and check a profile TOML file; every refusal is a ``ConfigError`` naming it."""
    data = read_toml(path, what="profile file", error=ConfigError)
    return Profile.from_mapping(data, source=os.fspath(path))


def load_profile(name_or_path: str | os.PathLike[str] = DEFAULT_PROFILE) -> Profile:
    """A shipped profile by name (``"lab"``) or a profile file by path (``"mine.toml"``)."""
    text = os.fspath(name_or_path)
    if isinstance(name_or_path, os.PathLike) or text.endswith(".toml") or is_regular_file(text):
        return read_profile_file(text)
    return read_profile_file(profile_path(text))


def write_profile_file(path: str | os.PathLike[str], profile: Profile) -> Path:
    """Write ``profile`` atomically in the TOML layout that ``read_profile_file`` reads back.

    Scalar scenario keys come first, then ``[profile]`` (with
    ``[profile.calibration]``), then the scenario tables. Returns the path.
    """
    # Imported here: reading profiles (every simulation) needs neither.
    import tomli_w  # noqa: PLC0415

    from swarmtag._atomic import atomic_write_bytes  # noqa: PLC0415

    values = profile.values
    scalars = {key: value for key, value in values.items() if not isinstance(value, Mapping)}
    tables = {key: value for key, value in values.items() if isinstance(value, Mapping)}
    document = {**scalars, _META: profile.to_mapping()[_META], **tables}
    try:
        text = tomli_w.dumps(document)
    except (TypeError, ValueError) as error:
        msg = f"{os.fspath(path)}: the profile cannot be written as TOML ({error})"
        raise ConfigError(msg) from None
    atomic_write_bytes(path, text.encode())
    return Path(path)
