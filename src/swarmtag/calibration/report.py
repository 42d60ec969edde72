"""The fit report: per set-up and KPI the target, its CI, what was achieved and the residual.

``fit_table`` gives the rows as text (the CLI prints them with rich);
``markdown_report`` writes the same table, the free parameters and the
search record as one Markdown document. Numbers show four significant digits.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Final

from swarmtag._checks import check_instance
from swarmtag.calibration.fit import SIGNIFICANT_DIGITS, CalibrationResult
from swarmtag.calibration.objective import UNDEFINED_PENALTY, KpiFit
from swarmtag.errors import CalibrationError

__all__ = ["FIT_COLUMNS", "fit_table", "format_number", "markdown_report", "summary_line"]

FIT_COLUMNS: Final = (
    "set-up",
    "KPI",
    "target",
    "95 % CI",
    "achieved",
    "residual",
    "inside CI?",
    "weight",
)
"""Columns of the fit table, in order."""


def format_number(value: float | None) -> str:
    """Four significant digits, ``n/a`` for an undefined value.

    >>> format_number(4979.0), format_number(0.26612), format_number(None)
    ('4979', '0.2661', 'n/a')
    """
    return "n/a" if value is None else f"{value:.4g}"


def _row(fit: KpiFit) -> tuple[str, ...]:
    target = fit.target
    return (
        fit.setup,
        target.kpi,
        format_number(target.value),
        f"[{format_number(target.low)}, {format_number(target.high)}]",
        format_number(fit.achieved),
        "undefined" if fit.residual is None else f"{fit.residual:+.3f}",
        "yes" if fit.inside else "no",
        f"{target.weight:g}" + ("" if target.weight else " (reported only)"),
    )


def fit_table(result: CalibrationResult) -> list[tuple[str, ...]]:
    """The rows of the fit table at the rounded point (columns ``FIT_COLUMNS``)."""
    check_instance("result", result, CalibrationResult, error=CalibrationError)
    return [_row(fit) for fit in result.evaluation.rows]


def summary_line(result: CalibrationResult) -> str:
    """One line: the objective at the rounded point, and how it was found."""
    search = result.search
    inside = sum(fit.inside for fit in result.evaluation.rows if fit.target.weight > 0)
    fitted = sum(fit.target.weight > 0 for fit in result.evaluation.rows)
    return (
        f"objective {result.objective:.6g} at the rounded point ({inside} of {fitted} fitted "
        f"KPIs inside their CI); {search.evaluations} search evaluations ({search.design} "
        f"Sobol + {search.evaluations - search.design} Nelder-Mead), {result.computed} "
        f"simulated, {result.reused} from the cache"
    )


def _markdown_table(header: tuple[str, ...], rows: Sequence[tuple[str, ...]]) -> list[str]:
    lines = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    lines += ["| " + " | ".join(cell.replace("|", "\\|") for cell in row) + " |" for row in rows]
    return lines


def markdown_report(result: CalibrationResult) -> str:
    """The fit report as Markdown: baseline, free parameters, fit table and search record."""
    check_instance("result", result, CalibrationResult, error=CalibrationError)
    problem = result.problem
    targets = problem.targets
    record = result.profile.calibration
    lines = [
        f"# Calibration of profile `{result.profile.name}`",
        "",
        (
            f"- baseline: `{targets.source}` ({targets.kind}, sha256 {targets.source_digest}), "
            f"condition `{targets.condition}`"
        ),
        f"- base profile: `{record['base_profile']}`; seed {problem.seed}; runs per set-up: "
        + ", ".join(f"{setup} {runs}" for setup, runs in record["runs"].items()),
        f"- model digest {problem.model}, swarmtag {record['swarmtag']}",
        f"- command: `{record['command']}`",
        f"- {summary_line(result)}",
        "",
        "## Fit",
        "",
        *_markdown_table(FIT_COLUMNS, fit_table(result)),
        "",
        (
            "Residual r = (achieved - target) / half-width, the half-width being the distance "
            "from the target to the CI bound on the side of the achieved value (at least 1 % "
            "of the target); |r| <= 1 lies inside the CI. Objective = sum of weight * r^2; an "
            f"undefined KPI adds weight * {UNDEFINED_PENALTY:g}."
        ),
        "",
        "## Free parameters",
        "",
    ]
    rows = [
        (
            p.key,
            f"{p.low:g}",
            f"{p.high:g}",
            "log" if p.log else "linear",
            f"{result.fitted[p.key]:g}",
            f"{result.best[p.key]:.8g}",
        )
        for p in problem.free
    ]
    header = ("key", "low", "high", "scale", f"fitted ({SIGNIFICANT_DIGITS} digits)", "best found")
    lines += _markdown_table(header, rows)
    search = result.search
    lines += [
        "",
        "## Search",
        "",
        (
            f"Scrambled Sobol design of {search.design} points (seed {problem.seed}), then "
            f"bounded Nelder-Mead from the best of them: {search.message}. Best objective "
            f"found {search.objective:.6g}; at the rounded point {result.objective:.6g}."
        ),
        "",
    ]
    steps = [
        (
            str(number),
            step.phase,
            *(f"{p.from_unit(u):.6g}" for p, u in zip(problem.free, step.unit, strict=True)),
            f"{step.objective:.6g}",
        )
        for number, step in enumerate(search.steps, start=1)
    ]
    lines += _markdown_table(("#", "phase", *(p.key for p in problem.free), "objective"), steps)
    if targets.notes:
        lines += ["", "## Notes", "", *(f"- {note}" for note in targets.notes)]
    return "\n".join(lines) + "\n"
