"""The KPIs of SPEC §5: per-run values and a condition's point estimates.

``run_values`` computes, for every run of a condition at once, the numbers
the bootstrap resamples and Mann-Whitney compares: deliveries, latency sum,
mean and P95 latency, throughput, and PA at each threshold.
``condition_kpis`` turns them into the condition's figures: pooled P95 and
mean latency, mean throughput over the runs that have one, PA (5-50 %),
deliveries per run, total deliveries and undelivered carriers.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Final

import numpy as np
from numpy.typing import NDArray

from swarmtag.analysis.alignment import CURVE_THRESHOLDS, PA_THRESHOLDS, priority_alignment
from swarmtag.analysis.latency import SortedLatencies, segment_percentile, sorted_latencies
from swarmtag.analysis.runs import ConditionRuns

__all__ = ["METRICS", "ConditionKPIs", "RunValues", "condition_kpis", "run_values"]

METRICS: Final = ("p95_latency", "mean_latency", "throughput", "pa", "deliveries_per_run")
"""The compared metrics, in the order of SPEC §8.2."""


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

    @property
    def n_runs(self) -> int:
        """Number of runs."""
        return len(self.run_ids)

    def per_run(self, metric: str) -> NDArray[np.float64]:
        """The per-run value Mann-Whitney compares for ``metric`` (one of ``METRICS``)."""
        values: dict[str, NDArray[np.float64]] = {
            "p95_latency": self.p95_latency,
            "mean_latency": self.mean_latency,
            "throughput": self.throughput,
            "pa": self.pa,
            "deliveries_per_run": self.deliveries.astype(np.float64),
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
    for array in (
        latency_sum,
        mean_latency,
        p95_latency,
        throughput,
        pa_by_threshold,
        pa,
        carriers,
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
    )


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

    def value(self, metric: str) -> float | None:
        """The figure of ``metric`` (one of ``METRICS``)."""
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
    pooled = values.latencies.values
    with_throughput = values.throughput[~np.isnan(values.throughput)]
    total = int(values.deliveries.sum())
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
    )
