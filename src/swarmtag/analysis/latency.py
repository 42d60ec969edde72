"""Latency (delivery time - order time) of delivered carriers, and exact percentiles of it.

Percentiles follow numpy's default method bit for bit (linear interpolation
at position ``q/100 * (n - 1)`` between order statistics), whether of one
sorted sample, of many sorted segments at once (per-run values), or of a
sample in which each element is repeated by a weight (a bootstrap resample;
see ``swarmtag.analysis.resampling``).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from swarmtag._checks import check_instance, check_int, check_sequence
from swarmtag.analysis.runs import ConditionRuns
from swarmtag.errors import StatisticsError

__all__ = [
    "SortedLatencies",
    "UrgencyLatency",
    "interpolation_points",
    "latency_by_urgency",
    "lerp",
    "segment_percentile",
    "sorted_latencies",
]


def interpolation_points(
    counts: NDArray[np.int64], q: float | NDArray[np.float64]
) -> tuple[NDArray[np.int64], NDArray[np.int64], NDArray[np.float64]]:
    """Lower and upper order-statistic indices and the weight between them, as numpy does.

    For each sample size ``n >= 1`` in ``counts``: position ``(n - 1) * q/100``,
    its floor, the next index (both clipped to ``n - 1``), and the fraction.
    ``counts`` and an array of percentiles ``q`` broadcast (``counts[:, None]``
    and ``q`` give one column per percentile), element by element the same.
    """
    fraction_of_one = np.true_divide(q, 100, dtype=np.float64)
    virtual = np.multiply(counts - 1, fraction_of_one, dtype=np.float64)
    lower = np.floor(virtual)
    gamma = virtual - lower
    lower_index = lower.astype(np.int64)
    upper_index = lower_index + 1
    at_top = virtual >= counts - 1
    lower_index = np.where(at_top, counts - 1, lower_index)
    upper_index = np.where(at_top, counts - 1, upper_index)
    return lower_index, upper_index, gamma


def lerp(
    low: NDArray[np.float64], high: NDArray[np.float64], t: NDArray[np.float64]
) -> NDArray[np.float64]:
    """Interpolate between neighbouring order statistics with numpy's very operations."""
    difference = high - low
    forward = low + difference * t
    backward = high - difference * (1 - t)
    return np.where(t >= 0.5, backward, forward)


def segment_percentile(
    values: NDArray[np.float64],
    starts: NDArray[np.int64],
    counts: NDArray[np.int64],
    q: float,
) -> NDArray[np.float64]:
    """The ``q``-th percentile of each sorted segment ``values[start:start+count]``; NaN if empty.

    >>> segment_percentile(np.array([1.0, 2.0, 3.0, 10.0, 20.0]), np.array([0, 3, 5]),
    ...     np.array([3, 2, 0]), 50)
    array([ 2., 15., nan])
    """
    result = np.full(len(counts), np.nan)
    present = counts > 0
    lower, upper, gamma = interpolation_points(counts[present], q)
    base = starts[present]
    result[present] = lerp(values[base + lower], values[base + upper], gamma)
    return result


@dataclass(frozen=True, eq=False)
class SortedLatencies:
    """All latencies of a condition in ascending order, with the run (index) of each."""

    values: NDArray[np.float64]
    runs: NDArray[np.intp]
    per_run: NDArray[np.int64]
    """How many latencies (deliveries) each run has."""

    @property
    def run_starts(self) -> NDArray[np.int64]:
        """Start of each run's block once latencies are sorted by (run, latency)."""
        return (np.cumsum(self.per_run) - self.per_run).astype(np.int64)

    def by_run(self) -> NDArray[np.float64]:
        """The latencies sorted by run first, then by value (blocks of ``per_run``)."""
        order = np.lexsort((self.values, self.runs))
        return self.values[order]


def sorted_latencies(runs: ConditionRuns) -> SortedLatencies:
    """The condition's latencies (delivered carriers only), pooled and sorted ascending."""
    delivered = runs.delivered
    latency = runs.delivery_time[delivered] - runs.order_time[delivered]
    run_of = runs.run_index[delivered]
    order = np.lexsort((run_of, latency))
    values, run_index = latency[order], run_of[order]
    per_run = np.bincount(run_of, minlength=runs.n_runs).astype(np.int64)
    for array in (values, run_index, per_run):
        array.flags.writeable = False
    return SortedLatencies(values=values, runs=run_index, per_run=per_run)


@dataclass(frozen=True)
class UrgencyLatency:
    """Pooled latency of the carriers with one urgency at run start (0-9).

    ``mean``, ``median`` and ``p95`` are ``None`` when none of them was delivered.
    """

    urgency: int
    carriers: int
    delivered: int
    mean: float | None
    median: float | None
    p95: float | None

    @property
    def undelivered(self) -> int:
        """Carriers of this urgency never delivered (they have no latency)."""
        return self.carriers - self.delivered


def latency_by_urgency(
    runs: ConditionRuns, levels: Sequence[int] = tuple(range(10))
) -> tuple[UrgencyLatency, ...]:
    """Pooled latency per urgency at run start: how long 9s wait compared with 0s.

    >>> from swarmtag.io import CarrierLog
    >>> log = CarrierLog(condition=["c"] * 3, run=[0, 0, 1], seed=[0] * 3, carrier=[1, 2, 1],
    ...     urgency0=[9, 9, 0], order_time=[-10.0, -20.0, 0.0], pickup_time=[1.0, 2.0, 3.0],
    ...     delivery_time=[10.0, 20.0, 5.0], robot=[0, 0, 0])
    >>> latency_by_urgency(ConditionRuns.from_log(log, "c"), levels=[9])
    (UrgencyLatency(urgency=9, carriers=2, delivered=2, mean=30.0, median=30.0, p95=39.0),)
    """
    check_instance("runs", runs, ConditionRuns, error=StatisticsError)
    levels = [
        check_int("levels", level, low=0, high=9, error=StatisticsError)
        for level in check_sequence("levels", levels, error=StatisticsError)
    ]
    delivered = runs.delivered
    latency = runs.delivery_time - runs.order_time
    result = []
    for level in levels:
        rows = runs.urgency0 == level
        sample = latency[rows & delivered]
        stats: tuple[float | None, float | None, float | None] = (None, None, None)
        if sample.size:
            median, p95 = np.percentile(sample, [50, 95])
            stats = (float(np.mean(sample)), float(median), float(p95))
        result.append(
            UrgencyLatency(
                urgency=int(level),
                carriers=int(rows.sum()),
                delivered=int(sample.size),
                mean=stats[0],
                median=stats[1],
                p95=stats[2],
            )
        )
    return tuple(result)
