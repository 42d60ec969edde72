"""Every condition of an event log against a baseline: the figures ``swarmtag metrics`` shows.

``summarize`` is pure (a log in, a report out); the JSON form of the report
is the contract of SPEC §8.2, extended: after each condition's SPEC keys come
the censoring-aware latencies (and PA at delivery where the log has
``urgency_end``) and ``runs_without_run_end``; after each comparison's SPEC
keys comes ``undelivered_differs``.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from functools import partial
from typing import Final

from swarmtag._checks import check_instance, check_sequence, check_text, show
from swarmtag._resources import check_memory, memory_limit
from swarmtag._threads import default_threads, map_in_threads
from swarmtag.analysis._kernels import use_compiled
from swarmtag.analysis._validation import check_compiled, check_options
from swarmtag.analysis.bootstrap import (
    ConditionStatistics,
    Estimate,
    _statistics,
    bootstrap_work,
)
from swarmtag.analysis.compare import Comparison, compare_all
from swarmtag.analysis.kpis import CORE_METRICS
from swarmtag.analysis.resampling import bootstrap_memory, one_blas_thread
from swarmtag.analysis.runs import split_conditions
from swarmtag.errors import StatisticsError
from swarmtag.io.tables import CarrierLog

__all__ = ["DEFAULT_BASELINE", "JsonValue", "MetricsReport", "choose_baseline", "summarize"]

DEFAULT_BASELINE: Final = "proximity"
"""The baseline when none is named (else the first condition in sorted order)."""

_LISTED: Final = 12
"""Conditions a refusal lists by name (a sweep may have many)."""

JsonValue = None | bool | int | float | str | list["JsonValue"] | dict[str, "JsonValue"]


def choose_baseline(conditions: Sequence[str], requested: str | None = None) -> str:
    """The requested baseline, else ``proximity``, else the first condition in sorted order.

    >>> choose_baseline(["urgency:alpha=0.7", "proximity"])
    'proximity'
    >>> choose_baseline(["weighted:w=0.5", "weighted:w=0.1"])
    'weighted:w=0.1'
    """
    conditions = [
        check_text("conditions", name, error=StatisticsError)
        for name in check_sequence("conditions", conditions, error=StatisticsError)
    ]
    if requested is not None:
        check_text("baseline", requested, error=StatisticsError)
    names = sorted(conditions)
    if not names:
        raise StatisticsError("the event log has no rows: there is nothing to analyse")
    if requested is not None:
        if requested not in names:
            raise StatisticsError(
                f"unknown baseline {requested!r}; the log has conditions {', '.join(names)}"
            )
        return requested
    return DEFAULT_BASELINE if DEFAULT_BASELINE in names else names[0]


def _estimate_json(estimate: Estimate) -> dict[str, JsonValue]:
    interval = estimate.confidence_interval
    return {"value": estimate.value, "ci": [interval.low, interval.high]}


@dataclass(frozen=True, eq=False)
class MetricsReport:
    """Statistics of every condition (baseline first, then sorted) and comparisons with it."""

    baseline: str
    n_resamples: int
    seed: int
    confidence_level: float
    time_unit: str | None
    conditions: tuple[ConditionStatistics, ...]
    comparisons: tuple[Comparison, ...]

    def condition(self, name: str) -> ConditionStatistics:
        """The statistics of one condition; ``StatisticsError`` naming the report's otherwise.

        The refusal shows at most a few dozen characters of what was asked for
        (a report or an array passed by mistake would otherwise fill the screen).
        """
        checked: object = name  # names come from notebooks and scripts, outside the type checker
        if isinstance(checked, str):
            for statistics in self.conditions:
                if statistics.condition == checked:
                    return statistics
        names = [s.condition for s in self.conditions]
        known = ", ".join(names[:_LISTED]) + (
            f", ... ({len(names)} in all)" if len(names) > _LISTED else ""
        )
        asked = (
            f"no condition {show(checked)}"
            if isinstance(checked, str)
            else f"a condition is named by a str, not a {type(checked).__name__}"
        )
        raise StatisticsError(f"{asked}; this report has {known}")

    def to_json(self) -> dict[str, JsonValue]:
        """The JSON object of SPEC §8.2 (``None`` becomes ``null``)."""
        conditions: list[JsonValue] = []
        for statistics in self.conditions:
            entry: dict[str, JsonValue] = {
                "condition": statistics.condition,
                "runs": statistics.kpis.runs,
            }
            for metric in CORE_METRICS:
                entry[metric] = _estimate_json(statistics.estimate(metric))
            entry["total_deliveries"] = statistics.kpis.total_deliveries
            entry["undelivered"] = statistics.kpis.undelivered
            for metric in statistics.metrics:
                if metric not in CORE_METRICS:  # the censored companions, then optional ones
                    entry[metric] = _estimate_json(statistics.estimate(metric))
            entry["runs_without_run_end"] = statistics.kpis.runs_without_run_end
            conditions.append(entry)
        comparisons: list[JsonValue] = [
            {
                "condition": comparison.condition,
                "baseline": comparison.baseline,
                "metric": comparison.metric,
                "diff": comparison.diff,
                "ci": [comparison.confidence_interval.low, comparison.confidence_interval.high],
                "p_bootstrap": comparison.p_bootstrap,
                "p_mannwhitney": comparison.p_mannwhitney,
                "undelivered_differs": comparison.undelivered_differs,
                "underpowered": comparison.underpowered,
                "smallest_p_mannwhitney": comparison.smallest_p,
            }
            for comparison in self.comparisons
        ]
        return {"conditions": conditions, "comparisons": comparisons}


def _conditions(count: int) -> str:
    return f"{count} condition" + ("" if count == 1 else "s")


def _threads(n_resamples: int, *, conditions: int, width: int) -> int:
    """Threads for the conditions' bootstraps: one a condition, up to ``default_threads()``.

    Fewer where the memory available would not hold that many at once
    (``bootstrap_memory``); where one does not fit either, the request is
    refused (``check_memory``) before anything is drawn.
    """
    need = partial(bootstrap_memory, n_resamples, conditions=conditions, width=width)
    limit = memory_limit()
    for threads in range(min(conditions, default_threads()), 1, -1):
        if need(threads=threads) <= limit:
            return threads
    estimate = need()
    check_memory(f"--resamples {n_resamples} over {_conditions(conditions)}", estimate)
    return 1


def summarize(
    log: CarrierLog,
    *,
    baseline: str | None = None,
    n_resamples: int = 10_000,
    seed: int = 0,
    confidence_level: float = 0.95,
    compiled: bool | None = None,
) -> MetricsReport:
    """KPIs with bootstrap intervals for every condition, and differences from the baseline.

    ``compiled``: evaluate the resamples with the compiled kernels (numba, the
    ``fast`` extra) or numpy; ``None`` picks the compiled ones where numba is
    installed and the work, all conditions together, pays for loading them.
    Same numbers either way.

    >>> from swarmtag.io import CarrierLog
    >>> log = CarrierLog(condition=["proximity", "urgency:alpha=3.0"], run=[0, 0], seed=[0, 0],
    ...     carrier=[1, 1], urgency0=[5, 5], order_time=[0.0, 0.0], pickup_time=[1.0, 1.0],
    ...     delivery_time=[20.0, 12.0], robot=[0, 0])
    >>> report = summarize(log, n_resamples=100)
    >>> [(c.metric, c.diff) for c in report.comparisons][:2]
    [('p95_latency', -8.0), ('mean_latency', -8.0)]

    What cannot fit in memory (``bootstrap_memory``: the bootstrap values
    kept for every condition and comparison) is refused with a
    ``swarmtag.errors.ResourceError`` before any resample is drawn.
    The conditions are bootstrapped on several threads at once (one a core,
    or ``SWARMTAG_THREADS``; fewer where memory is short): each draws from
    its own generator, so the numbers are the same on any number of threads.
    """
    check_instance("log", log, CarrierLog, error=StatisticsError)
    check_options(n_resamples=n_resamples, seed=seed, confidence_level=confidence_level)
    check_compiled(compiled)
    groups = split_conditions(log)
    chosen = choose_baseline(list(groups), baseline)
    order = [chosen, *(name for name in groups if name != chosen)]
    width = max(len(runs.carrier) for runs in groups.values())
    threads = _threads(n_resamples, conditions=len(order), width=width)
    if compiled is None:  # one choice for all: loading the compiled kernels pays off on the sum
        compiled = use_compiled(sum(bootstrap_work(n_resamples, runs) for runs in groups.values()))
    work = partial(
        _statistics,
        n_resamples=n_resamples,
        seed=seed,
        confidence_level=confidence_level,
        compiled=compiled,
    )
    with one_blas_thread():  # here, not only in each thread: one limit while they all run
        computed = map_in_threads(work, [groups[name] for name in order], threads)
    statistics = dict(zip(order, computed, strict=True))
    comparisons = tuple(
        comparison
        for name in order[1:]
        for comparison in compare_all(statistics[name], statistics[chosen])
    )
    return MetricsReport(
        baseline=chosen,
        n_resamples=n_resamples,
        seed=seed,
        confidence_level=confidence_level,
        time_unit=log.time_unit,
        conditions=tuple(statistics[name] for name in order),
        comparisons=comparisons,
    )
