"""Calibration targets: the KPIs a profile is fitted to, per set-up, from a file or an event log.

A target file (documented in docs/calibration.md, "Target files") holds a
``[calibration]`` table and one or more ``[[setups]]``; each set-up names the
runs to simulate, a scenario merged onto the base profile, and its KPI
targets ``{ value = ..., ci = [lo, hi], weight = 1.0 }``. (An event log of real
trials becomes the targets of one set-up instead: ``baseline.targets_from_log``.)
Every refusal is a ``CalibrationError`` naming the file and the key.
"""

from __future__ import annotations

import hashlib
import json
import math
import os
import re
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Final

from swarmtag._checks import check_path_value, check_text
from swarmtag._toml import read_toml
from swarmtag.analysis import kpis as _kpis
from swarmtag.errors import CalibrationError, ConfigError, SwarmtagError
from swarmtag.policy import parse_policy
from swarmtag.sim.config.mapping import scenario_fields

__all__ = [
    "COUNT_KPIS",
    "MAX_RUNS",
    "KpiTarget",
    "Setup",
    "Targets",
    "file_digest",
    "read_target_file",
    "target_kpis",
]

COUNT_KPIS: Final = ("total_deliveries", "undelivered")
"""Count KPIs: stated for the set-up's ``runs``; a simulation of other runs is scaled to them."""
MAX_RUNS: Final = 10_000
"""Most runs per set-up a calibration simulates at each evaluation."""
DIGEST_CHARS: Final = 16
"""Hex digits kept of a SHA-256 digest."""
_CALIBRATION_KEYS: Final = (
    "name",
    "description",
    "condition",
    "seed",
    "free",
    "evaluations",
    "time_unit",
)
_SETUP_KEYS: Final = ("name", "runs", "scenario", "kpis")
_KPI_KEYS: Final = ("value", "ci", "weight")
_SAFE_NAME: Final = re.compile(r"[A-Za-z0-9._-]+")


def target_kpis() -> tuple[str, ...]:
    """KPI names a target may name: every metric the analysis computes, then ``COUNT_KPIS``.

    Read from ``swarmtag.analysis.kpis`` when called, so a metric added there
    is a valid target at once.

    >>> target_kpis()[:3]
    ('p95_latency', 'mean_latency', 'throughput')
    """
    return (*_kpis.METRICS, *_kpis.OPTIONAL_METRICS, *COUNT_KPIS)


def file_digest(path: str | os.PathLike[str]) -> str:
    """The first 16 hex digits of the SHA-256 of a file's bytes."""
    return hashlib.sha256(Path(path).read_bytes()).hexdigest()[:DIGEST_CHARS]


def _number(value: object, key: str) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float) or not math.isfinite(value):
        msg = f"{key}: {value!r} is not a finite number"
        raise CalibrationError(msg)
    return float(value)


def _int(value: object, key: str, *, low: int, high: int) -> int:
    if isinstance(value, bool) or not isinstance(value, int) or not low <= value <= high:
        msg = f"{key}: {value!r} is not an integer in {low}-{high}"
        raise CalibrationError(msg)
    return value


def _name(value: object, key: str) -> str:
    if not isinstance(value, str) or not _SAFE_NAME.fullmatch(value):
        msg = f"{key}: {value!r} is not a name of letters, digits, '.', '_' and '-'"
        raise CalibrationError(msg)
    return value


def _table(value: object, key: str, allowed: Sequence[str] | None) -> dict[str, Any]:
    """``value`` as a dict if it is a table whose keys are all ``allowed`` (``None``: any)."""
    if not isinstance(value, Mapping):
        msg = f"{key}: {value!r} is not a table"
        raise CalibrationError(msg)
    unknown = [] if allowed is None else sorted(set(value) - set(allowed))
    if unknown:
        msg = f"{key}.{unknown[0]}: unknown key; {key} has keys {', '.join(sorted(allowed or ()))}"
        raise CalibrationError(msg)
    return dict(value)


@dataclass(frozen=True)
class KpiTarget:
    """One KPI to match: its value, its 95 % CI ``[low, high]`` and its weight (0: report only).

    >>> KpiTarget("pa", value=0.27, low=0.22, high=0.31).weight
    1.0
    >>> KpiTarget("pa", value=0.4, low=0.22, high=0.31)
    Traceback (most recent call last):
    ...
    swarmtag.errors.CalibrationError: pa: value 0.4 lies outside its ci [0.22, 0.31]
    """

    kpi: str
    value: float
    low: float
    high: float
    weight: float = 1.0

    def __post_init__(self) -> None:
        if self.kpi not in target_kpis():
            msg = f"{self.kpi}: not a KPI; targets may name {', '.join(target_kpis())}"
            raise CalibrationError(msg)
        for part in ("value", "low", "high", "weight"):
            _number(getattr(self, part), f"{self.kpi}.{part}")
        if self.weight < 0:
            msg = f"{self.kpi}.weight: {self.weight!r} is not a number >= 0"
            raise CalibrationError(msg)
        if not self.low <= self.value <= self.high:
            msg = f"{self.kpi}: value {self.value!r} lies outside its ci [{self.low!r}, "
            msg += f"{self.high!r}]"
            raise CalibrationError(msg)

    @classmethod
    def from_mapping(cls, kpi: str, data: object) -> KpiTarget:
        """A target from ``{ value = ..., ci = [lo, hi], weight = ... }`` (weight optional)."""
        table = _table(data, kpi, _KPI_KEYS)
        for required in ("value", "ci"):
            if required not in table:
                msg = f"{kpi}: {required} is missing (write ci = [v, v] for an exact target)"
                raise CalibrationError(msg)
        ci = table["ci"]
        if not isinstance(ci, list) or len(ci) != 2:
            msg = f"{kpi}.ci: {ci!r} is not a pair [lo, hi]"
            raise CalibrationError(msg)
        return cls(
            kpi,
            value=_number(table["value"], f"{kpi}.value"),
            low=_number(ci[0], f"{kpi}.ci[0]"),
            high=_number(ci[1], f"{kpi}.ci[1]"),
            weight=_number(table.get("weight", 1.0), f"{kpi}.weight"),
        )

    def to_mapping(self) -> dict[str, Any]:
        """The file form of this target."""
        return {"value": self.value, "ci": [self.low, self.high], "weight": self.weight}


@dataclass(frozen=True)
class Setup:
    """A set-up: ``runs`` runs of ``scenario`` (merged onto the profile) and its KPI targets."""

    name: str
    runs: int
    scenario: Mapping[str, Any]
    kpis: tuple[KpiTarget, ...]

    def __post_init__(self) -> None:
        _name(self.name, "name")
        _int(self.runs, "runs", low=1, high=MAX_RUNS)
        try:
            scenario_fields(self.scenario)  # unknown keys and bad tables, named
        except ConfigError as error:
            raise CalibrationError(f"scenario.{error}") from None
        if not self.kpis:
            raise CalibrationError("kpis: a set-up needs at least one KPI target")
        names = [target.kpi for target in self.kpis]
        if len(set(names)) != len(names):
            raise CalibrationError("kpis: a KPI is named twice")

    @classmethod
    def from_mapping(cls, data: object) -> Setup:
        """A set-up from its ``[[setups]]`` table."""
        table = _table(data, "setup", _SETUP_KEYS)
        for required in ("name", "runs", "kpis"):
            if required not in table:
                msg = f"{required} is missing"
                raise CalibrationError(msg)
        kpis = _table(table["kpis"], "kpis", target_kpis())
        return cls(
            name=table["name"],
            runs=table["runs"],
            scenario=_table(table.get("scenario", {}), "scenario", None),
            kpis=tuple(KpiTarget.from_mapping(kpi, spec) for kpi, spec in kpis.items()),
        )

    def to_mapping(self) -> dict[str, Any]:
        """The file form of this set-up."""
        return {
            "name": self.name,
            "runs": self.runs,
            "scenario": dict(self.scenario),
            "kpis": {target.kpi: target.to_mapping() for target in self.kpis},
        }


@dataclass(frozen=True)
class Targets:
    """A calibration baseline: the profile to write, the condition, the seed and the set-ups.

    ``source`` is what the user named (a shipped name, a target file or an
    event log) and ``source_digest`` the digest of that file's bytes;
    ``digest`` covers the content that decides the fit (set-ups, KPIs,
    condition), so it keys the evaluation cache. ``free`` and
    ``evaluations`` are the defaults a target file may suggest; ``time_unit``,
    when given, is the unit the base profile must log in. ``notes`` say what
    was left out (e.g. a KPI undefined in an event log).
    """

    name: str | None
    description: str
    condition: str
    seed: int
    setups: tuple[Setup, ...]
    source: str
    source_digest: str
    kind: str = "targets"
    """``"targets"`` (a target file or a shipped name) or ``"event log"``."""
    free: tuple[str, ...] = ()
    evaluations: int | None = None
    time_unit: str | None = None
    notes: tuple[str, ...] = field(default=())

    def __post_init__(self) -> None:
        if self.name is not None:
            _name(self.name, "calibration.name")
        try:
            parse_policy(self.condition)
        except SwarmtagError as error:
            raise CalibrationError(f"calibration.condition: {error}") from None
        _int(self.seed, "calibration.seed", low=0, high=2**63 - 1)
        if not self.setups:
            raise CalibrationError("setups: at least one [[setups]] table is needed")
        names = [setup.name for setup in self.setups]
        repeated = sorted({name for name in names if names.count(name) > 1})
        if repeated:
            raise CalibrationError(f"setups: set-up {repeated[0]!r} is named twice")
        if not any(target.weight > 0 for setup in self.setups for target in setup.kpis):
            raise CalibrationError("setups: every KPI has weight 0, so there is nothing to fit")
        if self.time_unit not in (None, "tick", "s"):
            msg = f"calibration.time_unit: {self.time_unit!r} is not 'tick' or 's'"
            raise CalibrationError(msg)

    @property
    def digest(self) -> str:
        """16 hex digits of the SHA-256 of the content that decides the fit."""
        content = {
            "condition": self.condition,
            "setups": [setup.to_mapping() for setup in self.setups],
        }
        text = json.dumps(content, sort_keys=True, separators=(",", ":"), allow_nan=False)
        return hashlib.sha256(text.encode()).hexdigest()[:DIGEST_CHARS]

    def setup(self, name: str) -> Setup:
        """The set-up called ``name``."""
        for setup in self.setups:
            if setup.name == name:
                return setup
        raise CalibrationError(f"no set-up {name!r} in {self.source}")

    @classmethod
    def from_mapping(cls, data: Mapping[str, Any], *, source: str, source_digest: str) -> Targets:
        """Targets from the layout of a target file; errors name ``source`` and the key."""
        try:
            top = _table(data, "target file", ("calibration", "setups"))
            meta = _table(top.get("calibration", {}), "calibration", _CALIBRATION_KEYS)
            setups = top.get("setups")
            if not isinstance(setups, list) or not setups:
                raise CalibrationError("setups: at least one [[setups]] table is needed")
            parsed = []
            for number, item in enumerate(setups):
                try:
                    parsed.append(Setup.from_mapping(item))
                except CalibrationError as error:
                    raise CalibrationError(f"setups[{number}]: {error}") from None
            free = meta.get("free", [])
            if not isinstance(free, list) or not all(isinstance(item, str) for item in free):
                msg = f"calibration.free: {free!r} is not a list of 'NAME=LO:HI[:log]' strings"
                raise CalibrationError(msg)
            evaluations = meta.get("evaluations")
            if evaluations is not None:
                evaluations = _int(evaluations, "calibration.evaluations", low=1, high=2**31)
            description = meta.get("description", "")
            if not isinstance(description, str):
                raise CalibrationError(f"calibration.description: {description!r} is not text")
            return cls(
                name=meta.get("name"),
                description=description,
                condition=meta.get("condition", "proximity"),
                seed=meta.get("seed", 0),
                setups=tuple(parsed),
                source=source,
                source_digest=source_digest,
                free=tuple(free),
                evaluations=evaluations,
                time_unit=meta.get("time_unit"),
            )
        except CalibrationError as error:
            raise CalibrationError(f"{source}: {error}") from None


def read_target_file(path: str | os.PathLike[str], *, source: str | None = None) -> Targets:
    """Read and check a target file; ``source`` names it in messages (default: the path)."""
    check_path_value("target file", path, error=CalibrationError)
    if source is not None:
        check_text("source", source, error=CalibrationError)
    data = read_toml(path, what="target file", error=CalibrationError)
    name = os.fspath(path) if source is None else source
    return Targets.from_mapping(data, source=name, source_digest=file_digest(path))
