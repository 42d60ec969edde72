"""The KPIs of SPEC §5: per-run values and a condition's point estimates.

``run_values`` computes, for every run of a condition at once, the numbers
the bootstrap resamples and Mann-Whitney compares: deliveries, latency sum,
mean and P95 latency, throughput, PA at each threshold, their censoring-aware
companions (``swarmtag.analysis.censoring``) and, where the log has
``urgency_end``, PA at delivery. ``condition_kpis`` turns them into the
condition's figures: pooled P95 and mean latency, mean throughput over the
runs that have one, PA (5-50 %), deliveries per run, total deliveries,
undelivered carriers, the censored P95 and mean, the Kaplan-Meier P95 and PA
at delivery.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Final

import numpy as np
from numpy.typing import NDArray

from swarmtag._checks import check_instance
from swarmtag.analysis._validation import check_thresholds
from swarmtag.analysis.alignment import CURVE_THRESHOLDS, PA_THRESHOLDS, priority_alignment
from swarmtag.analysis.censoring import CensoredLatencies, censored_latencies, km_quantile
from swarmtag.analysis.latency import SortedLatencies, segment_percentile, sorted_latencies
from swarmtag.analysis.runs import ConditionRuns
from swarmtag.errors import StatisticsError
from swarmtag.io.schema import MISSING_ID

__all__ = [
    "CENSORED_METRICS",
    "CORE_METRICS",
    "METRICS",
    "OPTIONAL_METRICS",
    "ConditionKPIs",
    "RunValues",
    "condition_kpis",
    "run_values",
]

CORE_METRICS: Final = ("p95_latency", "mean_latency", "throughput", "pa", "deliveries_per_run")
"""The five metrics of SPEC §8.2's JSON, in its order."""
CENSORED_METRICS: Final = ("p95_latency_censored", "mean_latency_censored", "km_p95_latency")
"""The censoring-aware latency companions (SPEC §5), after the core metrics everywhere."""
METRICS: Final = CORE_METRICS + CENSORED_METRICS
"""The metrics every condition has and every comparison covers, in output order."""
OPTIONAL_METRICS: Final = ("pa_at_delivery",)
"""Metrics present only when the log has their column (``urgency_end``), after ``METRICS``."""


@dataclass(frozen=True, eq=False)
class RunValues:
    """Per-run values of one condition (arrays follow ``run_ids``); NaN where a run has none."""

    condition: str
    run_ids: NDArray[np.int64]
    carriers: NDArray[np.int64]
    """Carriers in each run, delivered or not (PA's n)."""
    deliveries: NDArray[np.int64]
    latency_sum: NDArray[np.float64]
    mean_latency: NDArray[np.float64]
    """NaN for a run without deliveries."""
    p95_latency: NDArray[np.float64]
    """NaN for a run without deliveries."""
    throughput: NDArray[np.float64]
    """NaN for a run with fewer than two deliveries or with first == last delivery time."""
    thresholds: tuple[int, ...]
    """The thresholds of ``pa_by_threshold``: PA's 5-50 and the curve's."""
    pa_by_threshold: NDArray[np.float64]
    pa: NDArray[np.float64]
    """PA (5-50 %) of each run: the mean of PA(p) over p = 5, 10, ..., 50."""
    latencies: SortedLatencies
    censored: CensoredLatencies
    """Every carrier's latency, undelivered ones right-censored at run end."""
    censored_sum: NDArray[np.float64]
    mean_latency_censored: NDArray[np.float64]
    p95_latency_censored: NDArray[np.float64]
    has_urgency_end: bool
    """Whether any row of the condition has ``urgency_end`` (PA at delivery is then reported)."""
    pa_at_delivery: NDArray[np.float64]
    """PA (5-50 %) ranking by ``urgency_end``; NaN for a run in which a row lacks it."""

    @property
    def n_runs(self) -> int:
        """Number of runs."""
        return len(self.run_ids)

    def per_run(self, metric: str) -> NDArray[np.float64] | None:
        """The per-run value Mann-Whitney compares for ``metric``; ``None`` for the KM P95.

        ``metric`` is one of ``METRICS`` or ``OPTIONAL_METRICS``; the
        Kaplan-Meier P95 has no per-run value and no Mann-Whitney test.
        """
        values: dict[str, NDArray[np.float64] | None] = {
            "p95_latency": self.p95_latency,
            "mean_latency": self.mean_latency,
            "throughput": self.throughput,
            "pa": self.pa,
            "deliveries_per_run": self.deliveries.astype(np.float64),
            "p95_latency_censored": self.p95_latency_censored,
            "mean_latency_censored": self.mean_latency_censored,
            "km_p95_latency": None,
            "pa_at_delivery": self.pa_at_delivery,
        }
        return values[metric]

    def pa_curve(self, thresholds: Sequence[int]) -> NDArray[np.float64]:
        """Columns of ``pa_by_threshold`` for ``thresholds`` (each must have been computed)."""
        return self.pa_by_threshold[:, [self.thresholds.index(p) for p in thresholds]]


def _throughput(runs: ConditionRuns, deliveries: NDArray[np.int64]) -> NDArray[np.float64]:
    """``100 * n_delivered / (t_last - t_first)`` per run, NaN where undefined."""
    delivered = runs.delivered
    run_of = runs.run_index[delivered]
    times = runs.delivery_time[delivered]
    order = np.lexsort((times, run_of))
    times = times[order]
    starts = (np.cumsum(deliveries) - deliveries).astype(np.int64)
    some = deliveries > 0
    first = np.full(runs.n_runs, np.nan)
    last = np.full(runs.n_runs, np.nan)
    first[some] = times[starts[some]]
    last[some] = times[starts[some] + deliveries[some] - 1]
    has = (deliveries >= 2) & (last > first)
    result = np.full(runs.n_runs, np.nan)
    result[has] = 100 * deliveries[has] / (last[has] - first[has])
    return result


def run_values(
    runs: ConditionRuns, *, curve_thresholds: Sequence[int] = CURVE_THRESHOLDS
) -> RunValues:
    """All per-run values of a condition, vectorised over runs."""
    check_instance("runs", runs, ConditionRuns, error=StatisticsError)
    check_thresholds("curve_thresholds", curve_thresholds)
    latencies = sorted_latencies(runs)
    deliveries = latencies.per_run
    by_run = latencies.by_run()
    latency_sum = np.bincount(
        latencies.runs, weights=latencies.values, minlength=runs.n_runs
    ).astype(np.float64)
    mean_latency = np.full(runs.n_runs, np.nan)
    some = deliveries > 0
    mean_latency[some] = latency_sum[some] / deliveries[some]
    thresholds = tuple(sorted(set(PA_THRESHOLDS) | {int(p) for p in curve_thresholds}))
    pa_by_threshold = priority_alignment(runs, thresholds)
    pa_columns = [thresholds.index(p) for p in PA_THRESHOLDS]
    p95_latency = segment_percentile(by_run, latencies.run_starts, deliveries, 95)
    throughput = _throughput(runs, deliveries)
    pa = np.mean(pa_by_threshold[:, pa_columns], axis=1)
    carriers = runs.carriers_per_run()
    censored = censored_latencies(runs)
    censored_sum = np.bincount(
        censored.runs, weights=censored.values, minlength=runs.n_runs
    ).astype(np.float64)
    mean_latency_censored = censored_sum / carriers  # every run has at least one carrier
    p95_latency_censored = segment_percentile(
        censored.by_run(), censored.run_starts, censored.per_run, 95
    )
    pa_at_delivery = _pa_at_delivery(runs)
    for array in (
        latency_sum,
        mean_latency,
        p95_latency,
        throughput,
        pa_by_threshold,
        pa,
        carriers,
        censored_sum,
        mean_latency_censored,
        p95_latency_censored,
        pa_at_delivery,
    ):
        array.flags.writeable = False
    return RunValues(
        condition=runs.condition,
        run_ids=runs.run_ids,
        carriers=carriers,
        deliveries=deliveries,
        latency_sum=latency_sum,
        mean_latency=mean_latency,
        p95_latency=p95_latency,
        throughput=throughput,
        thresholds=thresholds,
        pa_by_threshold=pa_by_threshold,
        pa=pa,
        latencies=latencies,
        censored=censored,
        censored_sum=censored_sum,
        mean_latency_censored=mean_latency_censored,
        p95_latency_censored=p95_latency_censored,
        has_urgency_end=bool((runs.urgency_end != MISSING_ID).any()),
        pa_at_delivery=pa_at_delivery,
    )


def _pa_at_delivery(runs: ConditionRuns) -> NDArray[np.float64]:
    """PA (5-50 %) per run ranking by ``urgency_end``; NaN where a row of the run lacks it."""
    missing = np.bincount(
        runs.run_index, weights=runs.urgency_end == MISSING_ID, minlength=runs.n_runs
    )
    if (missing > 0).all():
        return np.full(runs.n_runs, np.nan)
    by_threshold = priority_alignment(runs, PA_THRESHOLDS, urgency=runs.urgency_end)
    return np.where(missing > 0, np.nan, np.mean(by_threshold, axis=1))


@dataclass(frozen=True)
class ConditionKPIs:
    """A condition's figures (SPEC §5); ``None`` where undefined (e.g. no deliveries at all)."""

    condition: str
    runs: int
    p95_latency: float | None
    mean_latency: float | None
    throughput: float | None
    pa: float
    deliveries_per_run: float
    total_deliveries: int
    undelivered: int
    p95_latency_censored: float
    """Lower bound: undelivered carriers count at run end - order time."""
    mean_latency_censored: float
    """Lower bound, likewise."""
    km_p95_latency: float | None
    """Kaplan-Meier P95; ``None`` where the KM curve never reaches 0.95."""
    pa_at_delivery: float | None
    """PA ranking by ``urgency_end``: ``None`` without it (see ``has_pa_at_delivery``)."""
    has_pa_at_delivery: bool
    carriers: int
    """Carriers in all runs, delivered or not."""
    runs_without_run_end: int
    """Runs whose end was taken from their latest pickup or delivery (no ``run_end``)."""

    def value(self, metric: str) -> float | None:
        """The figure of ``metric`` (one of ``METRICS`` or ``OPTIONAL_METRICS``)."""
        value: float | None = getattr(self, metric)
        return value


def condition_kpis(values: RunValues) -> ConditionKPIs:
    """Point estimates: pooled P95 and mean latency, run means of the rest.

    >>> from swarmtag.io import CarrierLog
    >>> nan = float("nan")
    >>> log = CarrierLog(condition=["c"] * 3, run=[0, 0, 1], seed=[0] * 3, carrier=[1, 2, 1],
    ...     urgency0=[9, 3, 5], order_time=[-10.0, 0.0, 0.0], pickup_time=[1.0, 2.0, nan],
    ...     delivery_time=[10.0, 30.0, nan], robot=[0, 1, -1])
    >>> kpis = condition_kpis(run_values(ConditionRuns.from_log(log, "c")))
    >>> kpis.mean_latency, kpis.throughput, kpis.deliveries_per_run, kpis.undelivered
    (25.0, 10.0, 1.0, 1)
    """
    check_instance("values", values, RunValues, error=StatisticsError)
    pooled = values.latencies.values
    with_throughput = values.throughput[~np.isnan(values.throughput)]
    total = int(values.deliveries.sum())
    censored = values.censored.values
    with_pa_at_delivery = values.pa_at_delivery[~np.isnan(values.pa_at_delivery)]
    return ConditionKPIs(
        condition=values.condition,
        runs=values.n_runs,
        p95_latency=float(np.percentile(pooled, 95)) if pooled.size else None,
        mean_latency=float(np.mean(pooled)) if pooled.size else None,
        throughput=float(np.mean(with_throughput)) if with_throughput.size else None,
        pa=float(np.mean(values.pa)),
        deliveries_per_run=total / values.n_runs,
        total_deliveries=total,
        undelivered=int(values.carriers.sum()) - total,
        p95_latency_censored=float(np.percentile(censored, 95)),
        mean_latency_censored=float(np.mean(censored)),
        km_p95_latency=km_quantile(values.censored, 95),
        pa_at_delivery=(float(np.mean(with_pa_at_delivery)) if with_pa_at_delivery.size else None),
        has_pa_at_delivery=values.has_urgency_end,
        carriers=int(values.carriers.sum()),
        runs_without_run_end=int((~values.censored.run_end_recorded).sum()),
    )
