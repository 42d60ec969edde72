"""Which rows the terminal tables leave out because they repeat others, and the note that says so.

The terminal (``swarmtag simulate``, ``swarmtag metrics``) shows every
figure that tells something; a row whose content follows from the others is
left out, with one note line naming what was left out and why:

- when no condition left a carrier undelivered, the censoring-aware rows
  (censored P95 and mean, KM P95: with nothing censored they are the
  delivered-only latencies again) and the undelivered counts (0 everywhere);
- a value row that is 0 [0, 0] in every condition (its differences are 0 too);
- a difference row that is 0 [0, 0] for every condition (e.g. deliveries per
  run when every run delivers every carrier);
- the runs row when every condition has the same number of runs (the table
  title says it instead: ``runs_each``).

The Markdown, LaTeX and HTML tables and ``--json`` keep every row: a paper
or a script reads the same rows whatever the data. Pure: a report in,
metric names and a sentence out.
"""

from __future__ import annotations

import re
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Final

from swarmtag.analysis.kpis import CENSORED_METRICS, CORE_METRICS, OPTIONAL_METRICS
from swarmtag.analysis.summary import MetricsReport
from swarmtag.analysis.tables import metric_label

__all__ = ["COUNT_ROWS", "ShownRows", "shown_rows", "zero_cell", "zero_rows"]

COUNT_ROWS: Final = ("total_deliveries", "undelivered")
"""The value table's integer rows (no CI), after the core metrics."""
_NUMBER: Final = re.compile(r"-?\d+(?:\.\d+)?")


@dataclass(frozen=True)
class ShownRows:
    """The rows the terminal shows of a report, and what it leaves out."""

    values: tuple[str, ...]
    """Rows of the value table, in order: metrics and ``COUNT_ROWS`` names."""
    differences: tuple[str, ...]
    """Metrics of the differences table, in order."""
    runs_each: int | None
    """The runs of every condition when they are all equal (no runs row), else ``None``."""
    left_out: tuple[str, ...]
    """One sentence per group of rows left out: which, and why."""

    @property
    def note(self) -> str | None:
        """The sentences of ``left_out`` in one line, or ``None`` when nothing was left out."""
        return " ".join(self.left_out) or None


def _all_zero(report: MetricsReport, metric: str) -> bool:
    """Whether every condition has ``metric`` at exactly 0 with the interval [0, 0]."""
    for statistics in report.conditions:
        if metric in COUNT_ROWS:
            if getattr(statistics.kpis, metric) != 0:
                return False
            continue
        if metric not in statistics.metrics:
            return False
        estimate = statistics.estimate(metric)
        interval = estimate.confidence_interval
        if (estimate.value, interval.low, interval.high) != (0, 0, 0):
            return False
    return True


def _differences_zero(report: MetricsReport, metric: str) -> bool:
    """Whether every comparison of ``metric`` is 0 with the interval [0, 0]."""
    found = [k for k in report.comparisons if k.metric == metric]
    return bool(found) and all(
        (k.diff, k.confidence_interval.low, k.confidence_interval.high) == (0, 0, 0) for k in found
    )


def shown_rows(report: MetricsReport) -> ShownRows:
    """The rows of ``report`` worth showing on a terminal (module docstring)."""
    unit = report.time_unit
    optional = tuple(m for m in OPTIONAL_METRICS if any(m in c.metrics for c in report.conditions))
    values = [*CORE_METRICS, *COUNT_ROWS, *CENSORED_METRICS, *optional]
    differences = [
        m
        for m in (*CORE_METRICS, *CENSORED_METRICS, *optional)
        if any(k.metric == m for k in report.comparisons)
    ]
    left_out = []
    if all(c.kpis.undelivered == 0 for c in report.conditions):
        values = [m for m in values if m not in (*CENSORED_METRICS, "undelivered")]
        differences = [m for m in differences if m not in CENSORED_METRICS]
        left_out.append(
            "Left out: the censored latencies, KM P95 and the undelivered counts (every "
            "carrier was delivered: nothing is censored, so they repeat the delivered-only rows)."
        )
    zero = [m for m in values if _all_zero(report, m)]
    if zero:
        values = [m for m in values if m not in zero]
        differences = [m for m in differences if m not in zero]
        labels = "; ".join(metric_label(m, unit) for m in zero)
        left_out.append(f"Left out as 0 [0, 0] in every condition (differences too): {labels}.")
    same = [m for m in differences if _differences_zero(report, m)]
    if same:
        differences = [m for m in differences if m not in same]
        labels = "; ".join(metric_label(m, unit) for m in same)
        left_out.append(f"Left out as 0 [0, 0] for every condition: the differences in {labels}.")
    runs = {c.kpis.runs for c in report.conditions}
    return ShownRows(
        values=tuple(values),
        differences=tuple(differences),
        runs_each=runs.pop() if len(runs) == 1 else None,
        left_out=tuple(left_out),
    )


def zero_cell(text: str) -> bool:
    """Whether a table cell shows only zeros: ``0``, ``0 [0, 0]`` (not ``n/a`` or ``unknown``).

    >>> zero_cell("0 [0, 0]"), zero_cell("0"), zero_cell("0.0500 [0, 0.1500]"), zero_cell("n/a")
    (True, True, False, False)
    """
    numbers = _NUMBER.findall(text)
    return (
        bool(numbers)
        and _NUMBER.sub("", text).strip(" [],") == ""
        and not any(float(n) for n in numbers)
    )


def zero_rows(rows: Sequence[Sequence[str]]) -> tuple[list[list[str]], list[str]]:
    """Rows (label, cells...) without those whose every cell is zero, and those rows' labels."""
    kept: list[list[str]] = []
    dropped: list[str] = []
    for row in rows:
        if row[1:] and all(zero_cell(cell) for cell in row[1:]):
            dropped.append(row[0])
        else:
            kept.append(list(row))
    return kept, dropped
