"""Study specifications: what a study runs, read from a TOML file and validated at the edge.

A study is a set of conditions (canonical policy names) run on one scenario,
or on several *scales* (one scenario each, as in the scalability study), for
a number of runs from one master seed. Every field is checked when the study
is built, and a refusal is a ``StudyError`` naming the file and the key
(``study.toml: conditions[2]: 'urgency:alpa=3' is not a condition ...``), so
a long study never fails an hour in on a typo.

The file layout (every key but ``name``, ``conditions`` and ``runs`` optional)::

    name = "controller-selection"
    description = "SPEC §6: proximity against urgency-aware selection"
    conditions = ["proximity", "urgency:alpha=0.7", "urgency:alpha=3.0"]
    baseline = "proximity"      # default: the first condition
    runs = 100
    quick_runs = 10             # runs under --quick (default: min(runs, 10))
    ticks = 3000                # run length; the time limit for static urgency
    urgency = "growing"         # urgency model: "growing" or "static"
    seed = 0                    # master seed of the runs and of the bootstrap
    profile = "paper-sim"       # profile of free parameters (a shipped name or a file)
    backend = "fast"            # simulation backend: "reference" or "fast" (default: fast
                                # where numba is installed; the results are the same bytes)
    resamples = 10000           # bootstrap resamples of the metrics
    chunk_runs = 10             # runs per unit of work (results do not depend on it)
    ranking = false             # the report's ranking table and Pareto figure of the conditions
    policy_files = ["rules.py:my_rule"]   # score rules of one's own, FILE relative to
                                # this file; each adds a condition named after its function

    [scenario]                  # swarmtag.sim.Scenario.from_mapping layout
    robots = 3
    carriers = 7

    [scales."5x10"]             # optional: one scenario per scale, merged onto [scenario]
    robots = 5
    carriers = 10
    ticks = 3000                # a scale may set its own run length
"""

from __future__ import annotations

import functools
import hashlib
import json
import math
import os
import re
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Final

from swarmtag import __version__
from swarmtag._checks import (
    MAX_RESAMPLES,
    MAX_RUN_INDEX,
    MAX_SEED,
    check_instance,
    check_int,
    check_path_value,
    check_text,
    show,
)
from swarmtag._sources import PACKAGE_ROOT, imported_sources
from swarmtag._toml import read_toml
from swarmtag.errors import ConfigError, PolicyError, StudyError
from swarmtag.policy import Policy, load_checked_rule, parse_policy
from swarmtag.sim import Scenario
from swarmtag.sim.backends import BACKENDS
from swarmtag.sim.config.parts import MAX_TICKS
from swarmtag.sim.config.profiles import DEFAULT_PROFILE, Profile, load_profile

__all__ = ["DEFAULT_SCALE", "MAX_NAME", "URGENCY_MODELS", "Scale", "Study", "read_study_file"]

DEFAULT_SCALE: Final = "default"
"""Key of the single scale of a study file without a ``[scales]`` table."""
URGENCY_MODELS: Final = ("growing", "static")
"""The urgency models a study may name (``swarmtag.sim.UrgencyModel.model``)."""
_REQUIRED: Final = ("name", "conditions", "runs")
_KEYS: Final = (
    "name",
    "description",
    "conditions",
    "baseline",
    "runs",
    "quick_runs",
    "ticks",
    "urgency",
    "seed",
    "profile",
    "backend",
    "resamples",
    "chunk_runs",
    "policy_files",
    "ranking",
    "scenario",
    "scales",
)
_SAFE_NAME: Final = re.compile(r"[A-Za-z0-9._-]+")
MAX_NAME: Final = 100
"""Longest study name or scale key: each names a folder (most file systems allow 255 bytes)."""
_DEFAULT_TICKS: Final = 3000
_DEFAULT_QUICK: Final = 10
MAX_CHUNK_RUNS: Final = 10_000
"""Most runs in one unit of work (one batch in one worker's memory)."""
# Keys the study sets itself: a scenario table naming them would be silently overridden.
_STUDY_OWNED: Final = ("ticks",)


def _int(value: object, key: str, *, low: int, high: int | None = None) -> int:
    return check_int(key, value, low=low, high=high, error=StudyError)


def _text(value: object, key: str) -> str:
    if not isinstance(value, str) or not value.strip():
        msg = f"{key}: {value!r} is not a non-empty string"
        raise StudyError(msg)
    return value


def _folder_name(value: object, key: str) -> str:
    """A folder name of the results: ``MAX_NAME`` letters, digits, ``.``, ``_`` or ``-`` at most."""
    text = _text(value, key)
    if len(text) > MAX_NAME:
        msg = (
            f"{key}: {text[:40]!r}... is {len(text)} characters long; "
            f"at most {MAX_NAME} (it names a folder)"
        )
        raise StudyError(msg)
    if not _SAFE_NAME.fullmatch(text) or text in {".", ".."}:
        msg = f"{key}: {text!r} may hold only letters, digits, '.', '_' and '-' (it names a folder)"
        raise StudyError(msg)
    return text


def _table(value: object, key: str) -> dict[str, Any]:
    if not isinstance(value, Mapping):
        msg = f"{key}: {value!r} is not a table of keys"
        raise StudyError(msg)
    return dict(value)


_MODEL_ENTRY: Final = ("sim", "simulation.py")
"""The module a simulated run goes through: the model is every source it imports."""


def model_sources() -> list[Path]:
    """The source files that decide a simulated run's rows: ``simulate`` and all it imports.

    Read statically (``swarmtag._sources``), lazy imports (the compiled
    backend) included; pictures and MCAP output (``sim/outputs/render.py``,
    ``mcap.py``) and the CLI are not imported by ``simulate``, so a change
    there leaves stored runs valid.
    """
    return imported_sources([PACKAGE_ROOT.joinpath(*_MODEL_ENTRY)], transitive=True)


@functools.cache
def model_digest() -> str:
    """First 12 hex digits of a SHA-256 over the model's source files (paths and bytes)."""
    digest = hashlib.sha256()
    for path in model_sources():
        digest.update(path.relative_to(PACKAGE_ROOT).as_posix().encode() + b"\0")
        digest.update(path.read_bytes() + b"\0")
    return digest.hexdigest()[:12]


def _scenario_hash(mapping: Mapping[str, Any]) -> str:
    """12 hex digits of the SHA-256 of the scenario's canonical JSON."""
    text = json.dumps(mapping, sort_keys=True, separators=(",", ":"), allow_nan=False)
    return hashlib.sha256(text.encode()).hexdigest()[:12]


@dataclass(frozen=True)
class Scale:
    """One scenario of a study, under a key (``"default"``, or e.g. ``"5x10"`` for a swarm size).

    ``code_version`` is ``swarmtag.__version__`` plus a hash of the full
    scenario mapping: stored runs are reused only while both are unchanged.
    """

    key: str
    scenario: Scenario

    def __post_init__(self) -> None:
        """Refuse a warm-up at or past the run's end now, not after every run (``kpi_log``)."""
        warehouse, end = self.scenario.warehouse, self.scenario.run_ticks
        if warehouse is None or (first := self.kpi_warmup("tick")) < end:
            return
        where = "scenario" if self.key == DEFAULT_SCALE else f"scales.{self.key}"
        msg = (
            f"{where}: warehouse.warmup: {warehouse.warmup:g} s is tick {first:g}, "
            f"not before the run's end at tick {end} ({end * self.scenario.tick:g} s); "
            "shorten the warm-up or lengthen the run (ticks)"
        )
        raise StudyError(msg)

    @property
    def code_version(self) -> str:
        """``"<version>+<scenario hash>.<model hash>"``, part of every stored run's key.

        The model hash covers the source of everything that decides a run's
        rows, so a changed kernel never reuses runs stored by the old one.
        """
        return f"{__version__}+{_scenario_hash(self.scenario.to_mapping())}.{model_digest()}"

    def kpi_warmup(self, time_unit: str | None) -> float:
        """Where this scale's KPI window starts, in a log's ``time_unit``: 0 but for a warehouse.

        A warehouse's ``warmup`` seconds, as the first tick at or after them
        (in ticks, or that tick in seconds), so that float rounding of
        ``warmup / tick`` never moves an order across the window's edge.
        """
        warehouse = self.scenario.warehouse
        if warehouse is None:
            return 0.0
        ticks = warehouse.warmup / self.scenario.tick
        nearest = round(ticks)
        first = (
            nearest
            if math.isclose(ticks, nearest, rel_tol=1e-9, abs_tol=1e-9)
            else math.ceil(ticks)
        )
        return float(first) if time_unit == "tick" else first * self.scenario.tick


@dataclass(frozen=True)
class Study:
    """A validated study: conditions, scales, run counts, seed and baseline (all checked).

    Build one with ``Study.from_mapping`` (a TOML table) or ``swarmtag.experiments.load_study``.
    """

    name: str
    conditions: tuple[str, ...]
    scales: tuple[Scale, ...]
    runs: int
    quick_runs: int
    seed: int = 0
    baseline: str = ""  # empty: the first condition
    urgency: str = "growing"
    resamples: int = 10_000
    chunk_runs: int = 10
    description: str = ""
    profile: str = DEFAULT_PROFILE
    backend: str | None = None
    """Simulation backend: ``reference``, ``fast``, or ``None`` for the default (results agree)."""
    source: str | None = field(default=None, compare=False)
    policy_files: tuple[str, ...] = ()
    """Score rules of one's own, ``FILE.py:FUNCTION`` with ``FILE`` absolute (loaded, checked)."""
    ranking: bool = False
    """The report ranks the conditions (a table and a Pareto figure per scale)."""
    rules_digest: str = field(default="", init=False, compare=False)
    """12 hex digits over the rule files' bytes and functions when loaded ('' without any):
    part of the store key (``study_key``), so an edited rule never reuses its old runs."""

    def __post_init__(self) -> None:
        _folder_name(self.name, "name")
        object.__setattr__(self, "policy_files", _rules(self.policy_files, None))
        object.__setattr__(self, "rules_digest", _rules_digest(self.policy_files))
        object.__setattr__(self, "conditions", _conditions(list(self.conditions)))
        object.__setattr__(self, "scales", tuple(self.scales))
        if not self.scales:
            raise StudyError("scales: a study needs at least one scale")
        keys = [scale.key for scale in self.scales]
        for scale in self.scales:
            _folder_name(scale.key, f"scales.{scale.key}")
            if keys.count(scale.key) > 1:
                msg = f"scales.{scale.key}: the key is used twice"
                raise StudyError(msg)
        if self.urgency not in URGENCY_MODELS:
            msg = f"urgency: {self.urgency!r} is not one of {', '.join(URGENCY_MODELS)}"
            raise StudyError(msg)
        _int(self.runs, "runs", low=1, high=MAX_RUN_INDEX)
        _int(self.quick_runs, "quick_runs", low=1, high=MAX_RUN_INDEX)
        if self.quick_runs > self.runs:
            msg = f"quick_runs: {self.quick_runs} is more than runs ({self.runs})"
            raise StudyError(msg)
        _int(self.seed, "seed", low=0, high=MAX_SEED)
        _int(self.resamples, "resamples", low=1, high=MAX_RESAMPLES)
        _int(self.chunk_runs, "chunk_runs", low=1, high=MAX_CHUNK_RUNS)
        if self.backend is not None and self.backend not in BACKENDS:
            msg = f"backend: {self.backend!r} is not one of {', '.join(BACKENDS)}"
            raise StudyError(msg)
        if not self.baseline:
            object.__setattr__(self, "baseline", self.conditions[0])
        if self.baseline not in self.conditions:
            msg = (
                f"baseline: {self.baseline!r} is not one of the conditions {list(self.conditions)}"
            )
            raise StudyError(msg)

    @classmethod
    def from_mapping(
        cls, data: Mapping[str, Any], *, source: str | None = None, base: Path | None = None
    ) -> Study:
        """A study from a TOML-layout mapping; ``source`` (a file name) prefixes every message.

        ``policy_files`` are read relative to ``base`` (the study file's
        folder; default: the working directory).
        """
        given: object = data  # checked at run time: a library entry point
        if not isinstance(given, Mapping):
            msg = f"data: {show(given)} is not a mapping (a TOML table)"
            raise StudyError(msg)
        if source is not None:
            source = check_text("source", source, error=StudyError)
        if base is not None:
            base = check_instance("base", base, Path, error=StudyError)
        try:
            return cls._parse(data, source, base)
        except (StudyError, ConfigError) as error:
            prefix = f"{source}: " if source else ""
            raise StudyError(f"{prefix}{error}") from None

    @classmethod
    def _parse(cls, data: Mapping[str, Any], source: str | None, base: Path | None) -> Study:
        data = _table(data, "study")
        for key in data:
            if key not in _KEYS:
                msg = f"{key}: unknown key; a study has keys {', '.join(_KEYS)}"
                raise StudyError(msg)
        for key in _REQUIRED:
            if key not in data:
                msg = f"{key}: missing; a study needs {', '.join(_REQUIRED)}"
                raise StudyError(msg)
        files = data.get("policy_files", [])
        if not isinstance(files, list):
            msg = f"policy_files: {files!r} is not a list of 'FILE.py:FUNCTION' strings"
            raise StudyError(msg)
        rules = _rules(tuple(files), base)
        conditions = _conditions(data["conditions"])
        conditions += tuple(
            name for name in (spec.rpartition(":")[2] for spec in rules) if name not in conditions
        )
        runs = _int(data["runs"], "runs", low=1, high=MAX_RUN_INDEX)
        urgency = data.get("urgency", "growing")
        if urgency not in URGENCY_MODELS:
            msg = f"urgency: {urgency!r} is not one of {', '.join(URGENCY_MODELS)}"
            raise StudyError(msg)
        _folder_name(data["name"], "name")
        ticks = _int(data.get("ticks", _DEFAULT_TICKS), "ticks", low=1, high=MAX_TICKS)
        profile_name = _text(data.get("profile", DEFAULT_PROFILE), "profile")
        try:
            profile = load_profile(profile_name)
        except ConfigError as error:
            raise StudyError(f"profile: {error}") from None
        return cls(
            name=_text(data["name"], "name"),
            description=str(data.get("description", "")),
            conditions=conditions,
            baseline=_text(data.get("baseline", conditions[0]), "baseline"),
            runs=runs,
            quick_runs=_int(
                data.get("quick_runs", min(runs, _DEFAULT_QUICK)),
                "quick_runs",
                low=1,
                high=MAX_RUN_INDEX,
            ),
            seed=_int(data.get("seed", 0), "seed", low=0, high=MAX_SEED),
            resamples=_int(data.get("resamples", 10_000), "resamples", low=1, high=MAX_RESAMPLES),
            chunk_runs=_int(data.get("chunk_runs", 10), "chunk_runs", low=1, high=MAX_CHUNK_RUNS),
            urgency=urgency,
            profile=profile_name,
            backend=data.get("backend"),
            scales=_scales(data, urgency, ticks, profile),
            source=source,
            policy_files=rules,
            ranking=_flag(data.get("ranking", False), "ranking"),
        )

    def policies(self) -> tuple[Policy, ...]:
        """The conditions as policies, in the study's order."""
        return tuple(parse_policy(name) for name in self.conditions)

    def scale(self, key: str) -> Scale:
        """The scale under ``key``; ``StudyError`` naming the keys there are otherwise."""
        for scale in self.scales:
            if scale.key == key:
                return scale
        msg = f"scale {key!r}: not in study {self.name!r} (scales: {self.scale_keys})"
        raise StudyError(msg)

    @property
    def scale_keys(self) -> tuple[str, ...]:
        """The scales' keys in file order."""
        return tuple(scale.key for scale in self.scales)

    def run_count(self, *, quick: bool = False) -> int:
        """Runs per condition and scale: ``quick_runs`` under ``quick``, else ``runs``."""
        return self.quick_runs if quick else self.runs


def _flag(value: object, key: str) -> bool:
    if not isinstance(value, bool):
        msg = f"{key}: {value!r} is not true or false"
        raise StudyError(msg)
    return value


def _rules_digest(specs: tuple[str, ...]) -> str:
    if not specs:
        return ""
    digest = hashlib.sha256()
    for spec in specs:
        path, _, function = spec.rpartition(":")
        digest.update(Path(path).read_bytes() + b"\0" + function.encode() + b"\0")
    return digest.hexdigest()[:12]


def _rules(specs: tuple[object, ...], base: Path | None) -> tuple[str, ...]:
    """Each ``FILE.py:FUNCTION`` loaded and checked, as ``ABSOLUTE-FILE:FUNCTION``."""
    resolved = []
    for index, spec in enumerate(specs):
        key = f"policy_files[{index}]"
        if not isinstance(spec, str):
            msg = f"{key}: {spec!r} is not a 'FILE.py:FUNCTION' string"
            raise StudyError(msg)
        try:
            load_checked_rule(spec, base=base)
        except PolicyError as error:
            raise StudyError(f"{key}: {error}") from None
        path, _, function = spec.rpartition(":")
        absolute = Path(path) if base is None else base / path
        resolved.append(f"{absolute.resolve()}:{function}")
    return tuple(resolved)


def _conditions(value: object) -> tuple[str, ...]:
    if not isinstance(value, list) or not value:
        msg = f"conditions: {value!r} is not a non-empty list of condition names"
        raise StudyError(msg)
    names: list[str] = []
    for index, item in enumerate(value):
        key = f"conditions[{index}]"
        if not isinstance(item, str):
            msg = f"{key}: {item!r} is not a condition name (a string)"
            raise StudyError(msg)
        try:
            policy = parse_policy(item)
        except PolicyError as error:
            msg = (
                f"{key}: {item!r} is not a condition (e.g. proximity, urgency:alpha=0.7, "
                f"weighted:w=0.3): {error}"
            )
            raise StudyError(msg) from None
        if policy.name in names:
            msg = f"{key}: {item!r} repeats condition {policy.name!r}"
            raise StudyError(msg)
        names.append(policy.name)
    return tuple(names)


def _scale_scenario(
    base: Mapping[str, Any],
    extra: Mapping[str, Any],
    where: str,
    setting: tuple[str, int, Profile],
) -> Scenario:
    """The scenario of one scale: the profile, the base table, the scale's keys, then run length.

    ``setting`` is the study's urgency model, run length and profile.
    """
    urgency, ticks, profile = setting
    overrides: dict[str, Any] = {key: value for key, value in extra.items() if key != "ticks"}
    run_length = _int(extra.get("ticks", ticks), f"{where}.ticks", low=1, high=MAX_TICKS)
    overrides["urgency.model"] = urgency
    if urgency == "growing":
        overrides["ticks"] = run_length
    else:
        overrides["urgency.static_time_limit"] = run_length
    try:
        return profile.scenario(base, overrides)
    except ConfigError as error:
        raise StudyError(f"{where}: {error}") from None


def _scales(
    data: Mapping[str, Any], urgency: str, ticks: int, profile: Profile
) -> tuple[Scale, ...]:
    base = _table(data.get("scenario", {}), "scenario")
    for key in _STUDY_OWNED:
        if key in base:
            msg = f"scenario.{key}: set the study's top-level '{key}' (or a scale's) instead"
            raise StudyError(msg)
    urgency_table = base.get("urgency")
    if isinstance(urgency_table, Mapping) and "model" in urgency_table:
        raise StudyError("scenario.urgency.model: set the study's top-level 'urgency' instead")
    if "scales" not in data:
        setting = (urgency, ticks, profile)
        return (Scale(DEFAULT_SCALE, _scale_scenario(base, {}, "scenario", setting)),)
    tables = _table(data["scales"], "scales")
    if not tables:
        raise StudyError("scales: the table is empty; remove it or name at least one scale")
    return tuple(
        Scale(
            key,
            _scale_scenario(
                base, _table(extra, f"scales.{key}"), f"scales.{key}", (urgency, ticks, profile)
            ),
        )
        for key, extra in tables.items()
    )


def read_study_file(path: str | os.PathLike[str]) -> Study:
    """Read and validate a study TOML file; every refusal is a ``StudyError`` naming the file."""
    path = check_path_value("path", path, error=StudyError)
    data = read_toml(path, what="study file", error=StudyError)
    return Study.from_mapping(data, source=Path(path).name, base=Path(path).parent)
