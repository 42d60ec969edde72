"""Censoring-aware latency (SPEC §5): undelivered carriers right-censored at run end - order time.

A policy that leaves more carriers undelivered can look better on
delivered-only latency. Here every carrier counts: a delivered one with its
latency (delivery - order time), an undelivered one with ``run end - order
time``, the least latency it can have had. Percentiles and means of these
values are therefore lower bounds. A run's end is the log's ``run_end``;
where a run has none, the latest time the run recorded (its last pickup or
delivery; 0 if it recorded none), which is earlier than the true end and so
gives a weaker lower bound.

The Kaplan-Meier quantile treats the same values as right-censored
observations. Its point value is that of ``scipy.stats.ecdf`` on
``scipy.stats.CensoredData``, computed with scipy's own operations in numpy
(scipy.stats is not imported for it); its bootstrap values (one per resample
of runs) come from the same product-limit formula evaluated with run
multiplicities as weights (``swarmtag.analysis._kernels``). Integer weights
make the two agree bit for bit (tested): a resample is the estimator on the
replicated sample.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Final

import numpy as np
from numpy.typing import NDArray

from swarmtag._checks import check_instance, check_number
from swarmtag.analysis._kernels import km_reached
from swarmtag.analysis.latency import SortedLatencies
from swarmtag.analysis.runs import ConditionRuns
from swarmtag.errors import StatisticsError

__all__ = [
    "KM_TOLERANCE",
    "CensoredLatencies",
    "censored_latencies",
    "km_quantile",
    "km_resampled_quantiles",
    "run_ends",
]

KM_TOLERANCE: Final = 1e-9
"""The Kaplan-Meier CDF reaches a level ``q`` when it is at least ``q - KM_TOLERANCE``.

The product-limit estimate is a product of ratios; without a tolerance its
rounding (0.94999999999999996 for an exact 0.95) could move the quantile.
"""


def run_ends(runs: ConditionRuns) -> tuple[NDArray[np.float64], NDArray[np.bool_]]:
    """Each run's end of observation, and whether the log recorded it (``run_end``).

    Without ``run_end`` a run ends at its latest pickup or delivery time, or
    at 0 if it recorded none.

    >>> from swarmtag.io import CarrierLog
    >>> nan = float("nan")
    >>> log = CarrierLog(condition=["c"] * 3, run=[0, 0, 1], seed=[0] * 3, carrier=[1, 2, 1],
    ...     urgency0=[5] * 3, order_time=[0.0] * 3, pickup_time=[4.0, 9.0, nan],
    ...     delivery_time=[6.0, nan, nan], robot=[0, -1, -1])
    >>> run_ends(ConditionRuns.from_log(log, "c"))
    (array([9., 0.]), array([False, False]))
    """
    check_instance("runs", runs, ConditionRuns, error=StatisticsError)
    recorded = np.zeros(runs.n_runs, dtype=bool)
    given = ~np.isnan(runs.run_end)
    recorded[runs.run_index[given]] = True
    ends = np.full(runs.n_runs, np.nan)
    ends[runs.run_index[given]] = runs.run_end[given]  # one value per run (checked by the log)
    latest = np.fmax(runs.pickup_time, runs.delivery_time)
    fallback = np.full(runs.n_runs, -np.inf)
    np.maximum.at(fallback, runs.run_index, np.where(np.isnan(latest), -np.inf, latest))
    fallback[np.isneginf(fallback)] = 0.0
    ends[~recorded] = fallback[~recorded]
    for array in (ends, recorded):
        array.flags.writeable = False
    return ends, recorded


@dataclass(frozen=True, eq=False)
class CensoredLatencies(SortedLatencies):
    """Every carrier's latency or censoring value, pooled and sorted ascending, with its run.

    ``values`` holds the latency if delivered, else run end - order time;
    ``per_run`` counts carriers (values) per run; ``run_starts`` and
    ``by_run`` are those of ``SortedLatencies``.
    """

    observed: NDArray[np.bool_]
    """True where the value is a delivery (an event), False where it is censored."""
    run_end: NDArray[np.float64]
    """The end of observation used for each run."""
    run_end_recorded: NDArray[np.bool_]
    """Whether each run's end came from the log's ``run_end`` (else the fallback)."""


def censored_latencies(runs: ConditionRuns) -> CensoredLatencies:
    """The condition's censoring-aware latencies: one value per carrier (see the module doc).

    >>> from swarmtag.io import CarrierLog
    >>> nan = float("nan")
    >>> log = CarrierLog(condition=["c"] * 2, run=[0, 0], seed=[0] * 2, carrier=[1, 2],
    ...     urgency0=[5] * 2, order_time=[-2.0, -5.0], pickup_time=[4.0, nan],
    ...     delivery_time=[6.0, nan], robot=[0, -1], run_end=[20.0, 20.0])
    >>> censored_latencies(ConditionRuns.from_log(log, "c")).values
    array([ 8., 25.])
    """
    check_instance("runs", runs, ConditionRuns, error=StatisticsError)
    ends, recorded = run_ends(runs)
    delivered = runs.delivered
    value = np.where(delivered, runs.delivery_time, ends[runs.run_index]) - runs.order_time
    order = np.lexsort((runs.run_index, value))
    values, run_index, observed = value[order], runs.run_index[order], delivered[order]
    per_run = runs.carriers_per_run()
    for array in (values, run_index, observed, per_run):
        array.flags.writeable = False
    return CensoredLatencies(
        values=values,
        observed=observed,
        runs=run_index,
        per_run=per_run,
        run_end=ends,
        run_end_recorded=recorded,
    )


def _km_cdf(
    values: NDArray[np.float64], observed: NDArray[np.bool_]
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """The distinct values of a sorted sample and the Kaplan-Meier CDF at each, as scipy's ecdf.

    Without censoring scipy takes the empirical CDF (events / n); with it, the
    product-limit estimate ``1 - cumprod((n - d) / n)`` over every distinct
    value. The same operations in the same order give the same bits, without
    importing scipy.stats (a second or so).
    """
    distinct, first, counts = np.unique(values, return_index=True, return_counts=True)
    if observed.all():
        return distinct, np.cumsum(counts) / np.float64(values.size)
    at_risk = values.size - first
    deaths = np.add.reduceat(observed.astype(np.int64), first)
    survival = np.cumprod((at_risk - deaths) / at_risk, dtype=np.float64)
    return distinct, 1 - survival


def km_quantile(latencies: CensoredLatencies, q: float = 95) -> float | None:
    """The ``q``-th percentile of the Kaplan-Meier latency distribution; ``None`` if never reached.

    The quantile is the smallest latency at which the estimated CDF reaches
    ``q / 100`` (a step function: no interpolation). With no undelivered
    carrier it is numpy's ``inverted_cdf`` percentile of the latencies. The
    CDF is ``scipy.stats.ecdf``'s on ``scipy.stats.CensoredData``, bit for
    bit (tested), computed here in numpy.

    >>> from swarmtag.io import CarrierLog
    >>> nan = float("nan")
    >>> log = CarrierLog(condition=["c"] * 3, run=[0] * 3, seed=[0] * 3, carrier=[1, 2, 3],
    ...     urgency0=[5] * 3, order_time=[0.0] * 3, pickup_time=[1.0, 2.0, nan],
    ...     delivery_time=[3.0, 7.0, nan], robot=[0, 0, -1], run_end=[10.0] * 3)
    >>> latencies = censored_latencies(ConditionRuns.from_log(log, "c"))
    >>> km_quantile(latencies, 50), km_quantile(latencies, 95) is None
    (7.0, True)
    """
    check_instance("latencies", latencies, CensoredLatencies, error=StatisticsError)
    q = check_number("q", q, low=0.0, high=100.0, error=StatisticsError)
    values = latencies.values
    if values.size == 0:
        return None
    distinct, cdf = _km_cdf(values, latencies.observed)
    reached = np.flatnonzero(cdf >= q / 100 - KM_TOLERANCE)
    return float(distinct[reached[0]]) if reached.size else None


def km_resampled_quantiles(
    latencies: CensoredLatencies,
    weights: NDArray[np.int64],
    q: float = 95,
    *,
    compiled: bool | None = None,
) -> NDArray[np.float64]:
    """``km_quantile`` of each resample, ``(B,)``; NaN where its KM curve never reaches ``q``.

    ``weights`` is ``(B, R)``: how often each run is in each resample. The
    product-limit estimate runs over the sample's distinct values with
    weighted counts at risk and weighted deaths, exactly as
    ``scipy.stats.ecdf`` does on the replicated sample (numpy or compiled,
    ``compiled``: see ``swarmtag.analysis._kernels``).
    """
    values = latencies.values
    result = np.full(weights.shape[0], np.nan)
    if values.size == 0 or weights.shape[0] == 0:
        return result
    found = km_reached(
        values,
        latencies.runs,
        latencies.observed,
        weights,
        q / 100 - KM_TOLERANCE,
        compiled=compiled,
    )
    hit = found >= 0
    result[hit] = values[found[hit]]
    return result
