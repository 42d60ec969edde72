"""Calibration (SPEC §4.6): fit a profile's free parameters to a baseline's KPIs.

A baseline is a target file (KPI values with CIs per set-up), a shipped
one by name (``TARGETS``), or an event log of real trials. The objective is
the weighted sum of squared residuals in CI half-widths, evaluated under
common random numbers (every evaluation simulates the same runs); a
scrambled Sobol design and bounded Nelder-Mead search the bounds; every
evaluation is cached so an interrupted calibration resumes. See
docs/calibration.md.

- ``load_baseline`` / ``read_target_file`` / ``targets_from_log`` give ``Targets``;
- ``parse_free`` gives a ``FreeParameter`` (``NAME=LO:HI[:log]``);
- ``CalibrationProblem`` checks targets, profile, settings and bounds together;
- ``calibrate`` runs the search and returns a ``CalibrationResult`` with the profile;
- ``residual`` / ``objective`` / ``fit_rows`` are the objective's definition;
- ``fit_table`` / ``markdown_report`` are the fit report.
"""

from __future__ import annotations

from swarmtag.calibration.baseline import load_baseline, targets_from_log
from swarmtag.calibration.cache import EvaluationCache, default_cache_path
from swarmtag.calibration.evaluate import Evaluation, Evaluator
from swarmtag.calibration.fit import (
    DEFAULT_EVALUATIONS,
    MAX_EVALUATIONS,
    SIGNIFICANT_DIGITS,
    CalibrationResult,
    calibrate,
    check_evaluations,
)
from swarmtag.calibration.free import MAX_FREE, FreeParameter, parse_free, parse_free_list
from swarmtag.calibration.objective import (
    UNDEFINED_PENALTY,
    KpiFit,
    fit_rows,
    half_width,
    objective,
    residual,
)
from swarmtag.calibration.problem import CalibrationProblem
from swarmtag.calibration.registry import TARGETS, target_path
from swarmtag.calibration.report import FIT_COLUMNS, fit_table, markdown_report
from swarmtag.calibration.search import SearchResult, SearchStep, search
from swarmtag.calibration.spec import (
    MAX_RUNS,
    KpiTarget,
    Setup,
    Targets,
    read_target_file,
    target_kpis,
)

__all__ = [
    "DEFAULT_EVALUATIONS",
    "FIT_COLUMNS",
    "MAX_EVALUATIONS",
    "MAX_FREE",
    "MAX_RUNS",
    "SIGNIFICANT_DIGITS",
    "TARGETS",
    "UNDEFINED_PENALTY",
    "CalibrationProblem",
    "CalibrationResult",
    "Evaluation",
    "EvaluationCache",
    "Evaluator",
    "FreeParameter",
    "KpiFit",
    "KpiTarget",
    "SearchResult",
    "SearchStep",
    "Setup",
    "Targets",
    "calibrate",
    "check_evaluations",
    "default_cache_path",
    "fit_rows",
    "fit_table",
    "half_width",
    "load_baseline",
    "markdown_report",
    "objective",
    "parse_free",
    "parse_free_list",
    "read_target_file",
    "residual",
    "search",
    "target_kpis",
    "target_path",
    "targets_from_log",
]
