"""Baselines: a shipped name, a target file, or an event log of real trials, as ``Targets``.

An event log (CSV or Parquet) becomes the targets of one set-up: the KPIs of
one of its conditions (``proximity`` unless named) with their bootstrap 95 %
CIs, computed exactly as ``swarmtag metrics`` does (10,000 resamples, seed
0), the robots (largest robot id + 1) and carriers per run taken from the
log, and as many runs as the log has. This is how a lab calibrates the
simulator to its own arena from a few baseline trials.
"""

from __future__ import annotations

import re
from pathlib import Path
from typing import Final

import numpy as np

from swarmtag._checks import check_instance, check_path_value, check_text
from swarmtag._inputs import is_regular_file
from swarmtag.analysis import CORE_METRICS, ConditionRuns, summarize
from swarmtag.calibration.registry import target_path
from swarmtag.calibration.spec import (
    KpiTarget,
    Setup,
    Targets,
    file_digest,
    read_target_file,
)
from swarmtag.errors import CalibrationError
from swarmtag.io import MISSING_ID, CarrierLog, read_event_log

__all__ = [
    "BOOTSTRAP_RESAMPLES",
    "BOOTSTRAP_SEED",
    "EVENT_LOG_SUFFIXES",
    "load_baseline",
    "targets_from_log",
]

EVENT_LOG_SUFFIXES: Final = (".csv", ".parquet", ".pq")
"""A ``--baseline`` ending in one of these is an event log."""
BOOTSTRAP_RESAMPLES: Final = 10_000
"""Resamples of an event log's CIs: those of ``swarmtag metrics``."""
BOOTSTRAP_SEED: Final = 0
"""Seed of an event log's CIs: that of ``swarmtag metrics``."""
_DEFAULT_CONDITION: Final = "proximity"


def _choose_condition(log: CarrierLog, requested: str | None, source: str) -> str:
    names = log.conditions
    if not names:
        raise CalibrationError(f"{source}: the event log has no rows")
    if requested is not None:
        if requested not in names:
            msg = f"--condition {requested!r}: {source} has conditions {', '.join(names)}"
            raise CalibrationError(msg)
        return requested
    if _DEFAULT_CONDITION in names:
        return _DEFAULT_CONDITION
    if len(names) == 1:
        return names[0]
    msg = f"{source} has conditions {', '.join(names)} and none is proximity: "
    msg += "name the baseline with --condition"
    raise CalibrationError(msg)


def _setup_name(source: str) -> str:
    """A set-up name from the log's file name (``trials-2024.csv`` -> ``trials-2024``)."""
    name = re.sub(r"[^A-Za-z0-9._-]+", "-", Path(source).stem).strip("-")
    return name or "baseline"


def targets_from_log(
    log: CarrierLog, *, source: str, source_digest: str, condition: str | None = None
) -> Targets:
    """The targets of one set-up from ``condition`` (default ``proximity``) of an event log.

    The KPIs are ``CORE_METRICS`` (weight 1), each with its bootstrap 95 %
    CI (widened to contain the point value if it does not); a KPI the log
    leaves undefined is left out, with a note.
    """
    check_instance("log", log, CarrierLog, error=CalibrationError)
    check_text("source", source, error=CalibrationError)
    check_text("source_digest", source_digest, error=CalibrationError)
    if condition is not None:
        check_text("condition", condition, error=CalibrationError)
    chosen = _choose_condition(log, condition, source)
    runs = ConditionRuns.from_log(log, chosen)
    carriers = runs.carriers_per_run()
    if carriers.min() != carriers.max():
        msg = f"{source}: the runs of {chosen} have {carriers.min()} to {carriers.max()} carriers; "
        msg += "calibration needs the same number of carriers in every run"
        raise CalibrationError(msg)
    robots = log.robot[(log.condition == chosen) & (log.robot != MISSING_ID)]
    if robots.size == 0:
        raise CalibrationError(f"{source}: no carrier of {chosen} names a robot")
    statistics = summarize(log, n_resamples=BOOTSTRAP_RESAMPLES, seed=BOOTSTRAP_SEED)
    statistics_of = statistics.condition(chosen)
    targets = []
    notes = []
    for metric in CORE_METRICS:
        estimate = statistics_of.estimate(metric)
        low, high = estimate.confidence_interval.low, estimate.confidence_interval.high
        if estimate.value is None or low is None or high is None:
            notes.append(f"{metric} is undefined in the baseline, so it is not a target")
            continue
        value = float(estimate.value)
        targets.append(
            KpiTarget(metric, value=value, low=min(float(low), value), high=max(float(high), value))
        )
    setup = Setup(
        name=_setup_name(source),
        runs=runs.n_runs,
        scenario={"robots": int(np.max(robots)) + 1, "carriers": int(carriers[0])},
        kpis=tuple(targets),
    )
    return Targets(
        name=None,
        description=f"Calibrated on the {chosen} runs of {Path(source).name}",
        condition=chosen,
        seed=0,
        setups=(setup,),
        source=source,
        source_digest=source_digest,
        kind="event log",
        time_unit=log.time_unit,
        notes=tuple(notes),
    )


def load_baseline(text: str, *, condition: str | None = None) -> Targets:
    """``--baseline``: an event log (.csv, .parquet), a target file (.toml) or a shipped name.

    ``condition`` picks an event log's condition; a target file names its own.
    """
    text = check_path_value("--baseline", text, error=CalibrationError)
    if condition is not None:
        check_text("--condition", condition, error=CalibrationError)
    path = Path(text)
    if path.suffix.lower() in EVENT_LOG_SUFFIXES:
        if not is_regular_file(path):
            raise CalibrationError(f"--baseline {text}: no such event log")
        log = read_event_log(path)
        return targets_from_log(
            log, source=text, source_digest=file_digest(path), condition=condition
        )
    if condition is not None:
        msg = "--condition picks an event log's condition; a target file names its own "
        msg += "([calibration] condition)"
        raise CalibrationError(msg)
    if text.endswith(".toml") or is_regular_file(path):
        return read_target_file(path, source=text)
    return read_target_file(target_path(text), source=text)
