"""Reports and event logs as pandas DataFrames: the only module of the package that imports pandas.

Imported on first use (``swarmtag.notebook`` itself stays free of pandas), so
a missing extra is one ``ImportError`` naming it. The numbers are the
report's own (``swarmtag.analysis``); this module only lays them out.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Final

import numpy as np

from swarmtag.analysis import CENSORED_METRICS, CORE_METRICS, Comparison, Estimate, MetricsReport
from swarmtag.io import MISSING_ID, TIME_UNIT_COLUMN, CarrierLog, EventTable, Kind
from swarmtag.notebook._result import PANDAS_HINT

try:
    import pandas as pd
except ImportError as error:  # pragma: no cover - the test environment has the extra
    raise ImportError(PANDAS_HINT) from error

__all__ = ["comparison_frame", "kpi_frame", "table_frame"]

COUNTS: Final = ("runs", "total_deliveries", "undelivered")
"""Integer columns of the KPI frame (no interval)."""


def _value(value: float | None) -> float:
    """A figure as a float: NaN where it is undefined (``None`` in the report and its JSON)."""
    return np.nan if value is None else float(value)


def _estimate(row: dict[str, object], metric: str, estimate: Estimate | None) -> None:
    """``metric``, ``metric_low`` and ``metric_high`` of ``row`` (NaN where absent)."""
    interval = None if estimate is None else estimate.confidence_interval
    row[metric] = _value(None if estimate is None else estimate.value)
    row[f"{metric}_low"] = _value(None if interval is None else interval.low)
    row[f"{metric}_high"] = _value(None if interval is None else interval.high)


def kpi_frame(report: MetricsReport, order: Sequence[str]) -> pd.DataFrame:
    """One row per condition (index ``condition``, in ``order``): the KPIs with 95 % CIs.

    Columns in the order of ``swarmtag simulate --json``: ``runs``, the core
    metrics (each with ``_low`` and ``_high``), ``total_deliveries``,
    ``undelivered``, the censoring-aware latencies, then PA at delivery where
    the log has it.
    """
    optional = [
        metric
        for metric in dict.fromkeys(m for s in report.conditions for m in s.metrics)
        if metric not in CORE_METRICS and metric not in CENSORED_METRICS
    ]
    rows = []
    for name in order:
        statistics = report.condition(name)
        row: dict[str, object] = {"runs": statistics.kpis.runs}
        for metric in CORE_METRICS:
            _estimate(row, metric, statistics.estimate(metric))
        row["total_deliveries"] = statistics.kpis.total_deliveries
        row["undelivered"] = statistics.kpis.undelivered
        for metric in (*CENSORED_METRICS, *optional):
            present = metric in statistics.metrics
            _estimate(row, metric, statistics.estimate(metric) if present else None)
        rows.append(row)
    frame = pd.DataFrame(rows, index=pd.Index(list(order), name="condition"))
    return frame.astype(dict.fromkeys(COUNTS, "int64"))


def comparison_frame(comparisons: Sequence[Comparison]) -> pd.DataFrame:
    """One row per condition and metric: the difference from the baseline, its CI and p-values.

    ``underpowered`` marks fewer than ``swarmtag.analysis.compare.MIN_RUNS``
    runs on a side (read Mann-Whitney then; ``smallest_p_mannwhitney`` is the
    lowest p it could give); ``undelivered_differs`` that delivered-only
    latency compares different sets of carriers (read the censored ones).
    """
    rows = [
        {
            "condition": c.condition,
            "baseline": c.baseline,
            "metric": c.metric,
            "diff": _value(c.diff),
            "ci_low": _value(c.confidence_interval.low),
            "ci_high": _value(c.confidence_interval.high),
            "p_bootstrap": _value(c.p_bootstrap),
            "p_mannwhitney": _value(c.p_mannwhitney),
            "underpowered": c.underpowered,
            "smallest_p_mannwhitney": c.smallest_p,
            "undelivered_differs": c.undelivered_differs,
        }
        for c in comparisons
    ]
    columns = ["condition", "baseline", "metric", "diff", "ci_low", "ci_high"]
    columns += ["p_bootstrap", "p_mannwhitney", "underpowered", "smallest_p_mannwhitney"]
    columns += ["undelivered_differs"]
    return pd.DataFrame(rows, columns=columns)


def table_frame(table: CarrierLog | EventTable) -> pd.DataFrame:
    """The columns a file of ``table`` holds (SPEC §8.1), with ``time_unit`` where known.

    Empty times stay NaN; empty robots and carriers (``MISSING_ID`` in
    memory) become pandas' missing value in a nullable ``Int64`` column, as
    in a Parquet file.
    """
    data: dict[str, object] = {}
    for spec in table.written_columns():
        column = getattr(table, spec.name)
        if spec.kind is Kind.INT and spec.nullable:
            missing = column == MISSING_ID
            data[spec.name] = pd.arrays.IntegerArray(np.where(missing, 0, column), missing)
        elif spec.kind is Kind.TEXT:
            data[spec.name] = column.tolist()
        else:
            data[spec.name] = np.array(column)  # a writable copy: the log's arrays are read-only
    if table.time_unit is not None:
        data[TIME_UNIT_COLUMN] = [table.time_unit] * len(table)
    return pd.DataFrame(data)
