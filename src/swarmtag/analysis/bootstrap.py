"""Bootstrap over runs (SPEC §5.1): percentile intervals for every KPI and curve of a condition.

A resample draws the condition's runs with replacement (as many as it has)
and recomputes each figure; pooled figures (P95 and mean latency) are
re-pooled from the resampled runs. The interval is the 2.5th and 97.5th
percentile of the bootstrap values (numpy's default method) for a 95 % level.

A figure can be undefined in a resample even when it is defined for the
condition: latency when the resample holds only runs without deliveries,
throughput when it holds only runs without one, the Kaplan-Meier P95 when
the resample's KM curve never reaches 0.95. Such resamples are left out of
that figure's interval (``Estimate.n_undefined`` counts them); when no
resample defines it, the interval is ``(None, None)``. The KM P95 of a
condition whose own KM curve never reaches 0.95 is undefined outright: its
bootstrap values are all undefined, so its interval and differences are too.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from swarmtag._checks import check_array, check_instance
from swarmtag._resources import check_memory
from swarmtag.analysis._kernels import use_compiled
from swarmtag.analysis._validation import check_compiled, check_level, check_options
from swarmtag.analysis.alignment import CURVE_THRESHOLDS
from swarmtag.analysis.censoring import km_resampled_quantiles
from swarmtag.analysis.curves import LATENCY_PERCENTILES, Curve, interval_percentiles
from swarmtag.analysis.kpis import (
    METRICS,
    OPTIONAL_METRICS,
    ConditionKPIs,
    RunValues,
    condition_kpis,
    run_values,
)
from swarmtag.analysis.resampling import (
    CHUNK_ELEMENTS,
    bootstrap_memory,
    condition_generator,
    iter_multiplicities,
    one_blas_thread,
    resampled_percentiles,
)
from swarmtag.analysis.runs import ConditionRuns
from swarmtag.errors import StatisticsError

__all__ = [
    "ConditionStatistics",
    "ConfidenceInterval",
    "Estimate",
    "bootstrap_work",
    "condition_statistics",
    "percentile_interval",
]


@dataclass(frozen=True)
class ConfidenceInterval:
    """Bounds of a confidence interval; ``None`` when no bootstrap value was defined."""

    low: float | None
    high: float | None


def percentile_interval(
    replicates: ArrayLike, *, confidence_level: float = 0.95
) -> ConfidenceInterval:
    """The percentile interval of bootstrap values, leaving out undefined (NaN) ones.

    >>> percentile_interval(np.arange(101.0))
    ConfidenceInterval(low=2.5, high=97.5)
    >>> percentile_interval([np.nan, np.nan])
    ConfidenceInterval(low=None, high=None)
    """
    level = check_level(confidence_level)
    values = check_array("replicates", replicates, nan=True, error=StatisticsError)
    defined = values[~np.isnan(values)]
    if defined.size == 0:
        return ConfidenceInterval(low=None, high=None)
    with np.errstate(over="ignore", invalid="ignore"):  # judged just below
        low, high = np.percentile(defined, interval_percentiles(level))
    if not low <= high:  # the spread overflowed float64 (values near ±1.8e308)
        raise StatisticsError("replicates: their spread overflows float64; rescale them first")
    return ConfidenceInterval(low=float(low), high=float(high))


@dataclass(frozen=True, eq=False)
class Estimate:
    """A figure, its bootstrap values (NaN where undefined) and its percentile interval."""

    value: float | None
    confidence_interval: ConfidenceInterval
    bootstrap_distribution: NDArray[np.float64]

    @property
    def n_undefined(self) -> int:
        """Resamples in which the figure was undefined (left out of the interval)."""
        return int(np.isnan(self.bootstrap_distribution).sum())


@dataclass(frozen=True, eq=False)
class ConditionStatistics:
    """Every figure of one condition with its bootstrap interval, plus the curves.

    ``values`` holds the per-run values (used by Mann-Whitney); the
    estimates' bootstrap values are paired by resample index, so a difference
    between two conditions can be bootstrapped from them directly.
    """

    condition: str
    kpis: ConditionKPIs
    values: RunValues
    n_resamples: int
    seed: int
    confidence_level: float
    p95_latency: Estimate
    mean_latency: Estimate
    throughput: Estimate
    pa: Estimate
    deliveries_per_run: Estimate
    pa_curve: Curve
    latency_curve: Curve
    p95_latency_censored: Estimate
    mean_latency_censored: Estimate
    km_p95_latency: Estimate
    pa_at_delivery: Estimate | None
    """``None`` when the condition's log has no ``urgency_end``."""

    @property
    def metrics(self) -> tuple[str, ...]:
        """The metrics this condition has: ``METRICS``, then PA at delivery where present."""
        return METRICS + (OPTIONAL_METRICS if self.pa_at_delivery is not None else ())

    def estimate(self, metric: str) -> Estimate:
        """The estimate of ``metric`` (one of ``metrics``)."""
        estimate: Estimate | None = getattr(self, metric) if metric in self.metrics else None
        if estimate is None:
            raise StatisticsError(
                f"unknown metric {metric!r} for {self.condition}; "
                f"expected one of {', '.join(self.metrics)}"
            )
        return estimate


def _ratio(numerator: NDArray[np.float64], denominator: NDArray[np.float64]) -> NDArray[np.float64]:
    out = np.full(numerator.shape, np.nan)
    np.divide(numerator, denominator, out=out, where=denominator > 0)
    return out


def bootstrap_work(n_resamples: int, runs: ConditionRuns) -> int:
    """Resamples x values the bootstrap of a condition walks: what ``use_compiled`` weighs.

    Each resample walks the delivered latencies once and every carrier's
    censoring-aware value twice (its P95, its Kaplan-Meier crossing).
    """
    return n_resamples * (int(np.count_nonzero(runs.delivered)) + 2 * len(runs.carrier))


def _replicates(
    values: RunValues,
    *,
    n_resamples: int,
    seed: int,
    curve_thresholds: Sequence[int],
    curve_percentiles: Sequence[float],
    chunk_elements: int,
    km: bool = True,
    compiled: bool | None = None,
) -> tuple[dict[str, NDArray[np.float64]], NDArray[np.float64], NDArray[np.float64]]:
    """Bootstrap values of every metric ``(B,)``, of the PA curve and of the latency curve.

    The curves' values come as ``(B, K)`` views of ``(K, B)`` arrays, so that
    each point's ``B`` values are contiguous for its band. Resamples are
    drawn and evaluated chunk by chunk (``iter_multiplicities``): only the
    ``B`` values per figure are ever stored, each exactly once.

    Percentiles and Kaplan-Meier quantiles come from the once-sorted values
    and each resample's run multiplicities (``swarmtag.analysis._kernels``:
    numpy, or compiled where ``compiled`` or ``use_compiled`` says so; the
    same numbers either way). Without ``km`` (the condition's own KM curve
    never reaches 0.95, so the bootstrap reports its KM P95 undefined) the
    Kaplan-Meier values are left NaN and not computed.

    Columns of the per-run sums: latency sum, deliveries, throughput and
    whether defined, PA, censored latency sum, carriers, PA at delivery and
    whether defined, then the PA curve.
    """
    n_runs = values.n_runs
    throughput = values.throughput
    has_throughput = ~np.isnan(throughput)
    has_pa_end = ~np.isnan(values.pa_at_delivery)
    per_run = np.column_stack(
        [
            values.latency_sum,
            values.deliveries,
            np.where(has_throughput, throughput, 0.0),
            has_throughput,
            values.pa,
            values.censored_sum,
            values.carriers,
            np.where(has_pa_end, values.pa_at_delivery, 0.0),
            has_pa_end,
            values.pa_curve(curve_thresholds),
        ]
    ).astype(np.float64)
    percentiles = [95, *curve_percentiles]
    names = METRICS + OPTIONAL_METRICS
    metrics = [np.empty(n_resamples) for _ in names]  # one array each: kept, never copied
    pa_curve = np.empty((len(curve_thresholds), n_resamples))
    # Row 0: the P95 (copied to its own array at the end), then the latency curve's points;
    # the percentiles are written straight into these rows, chunk by chunk.
    pooled = np.empty((len(percentiles), n_resamples))
    latencies = values.latencies
    censored = values.censored
    uncensored = np.array_equal(censored.values, latencies.values) and np.array_equal(
        censored.runs, latencies.runs
    )
    if compiled is None:  # as bootstrap_work counts
        compiled = use_compiled(n_resamples * (latencies.values.size + 2 * censored.values.size))
    rng = condition_generator(seed, values.condition)
    chunks = iter_multiplicities(
        rng,
        n_runs,
        n_resamples,
        width=max(n_runs, latencies.values.size, censored.values.size),
        chunk_elements=chunk_elements,
        compiled=compiled,
    )
    start = 0
    with one_blas_thread():  # products of chunks too small for BLAS threads
        for weights in chunks:
            stop = start + len(weights)
            sums = weights.astype(np.float64) @ per_run
            resampled_percentiles(
                latencies.values,
                latencies.runs,
                weights,
                percentiles,
                compiled=compiled,
                out=pooled[:, start:stop].T,
            )
            metrics[1][start:stop] = _ratio(sums[:, 0], sums[:, 1])
            metrics[2][start:stop] = _ratio(sums[:, 2], sums[:, 3])
            metrics[3][start:stop] = sums[:, 4] / n_runs
            metrics[4][start:stop] = sums[:, 1] / n_runs
            metrics[5][start:stop] = (
                pooled[0, start:stop]  # every carrier delivered: the same values, the same P95
                if uncensored
                else resampled_percentiles(
                    censored.values, censored.runs, weights, [95], compiled=compiled
                )[:, 0]
            )
            metrics[6][start:stop] = _ratio(sums[:, 5], sums[:, 6])
            # Evaluated for every chunk, on no resample where the figure is undefined outright.
            km_values = km_resampled_quantiles(
                censored, weights if km else weights[:0], 95, compiled=compiled
            )
            metrics[7][start:stop] = km_values if km else np.nan
            metrics[8][start:stop] = _ratio(sums[:, 7], sums[:, 8])
            pa_curve[:, start:stop] = (sums[:, 9:] / n_runs).T
            start = stop
    metrics[0][:] = pooled[0]
    for replicate in metrics:
        replicate.flags.writeable = False
    by_metric = dict(zip(names, metrics, strict=True))
    return by_metric, pa_curve.T, pooled[1:].T


def condition_statistics(
    runs: ConditionRuns,
    *,
    n_resamples: int = 10_000,
    seed: int = 0,
    confidence_level: float = 0.95,
    curve_thresholds: Sequence[int] = CURVE_THRESHOLDS,
    curve_percentiles: Sequence[float] = LATENCY_PERCENTILES,
    compiled: bool | None = None,
    _chunk_elements: int = CHUNK_ELEMENTS,
) -> ConditionStatistics:
    """KPIs of one condition with bootstrap-over-runs intervals, and its curves with bands.

    The resamples come from a generator keyed by ``seed`` and the condition's
    name, so they do not depend on which other conditions are analysed.
    ``compiled``: evaluate them with the compiled kernels (numba, the
    ``fast`` extra) or numpy; ``None`` picks the compiled ones where numba is
    installed and the work pays for loading them. Same numbers either way.

    >>> from swarmtag.io import CarrierLog
    >>> log = CarrierLog(condition=["c"] * 4, run=[0, 1, 2, 3], seed=[0] * 4, carrier=[1] * 4,
    ...     urgency0=[5] * 4, order_time=[0.0] * 4, pickup_time=[1.0] * 4,
    ...     delivery_time=[10.0, 20.0, 30.0, 40.0], robot=[0] * 4)
    >>> stats = condition_statistics(ConditionRuns.from_log(log, "c"), n_resamples=2000)
    >>> stats.mean_latency.value
    25.0
    >>> ci = stats.mean_latency.confidence_interval
    >>> 10.0 <= ci.low < 25.0 < ci.high <= 40.0
    True

    A request that cannot fit in memory is refused before anything is drawn
    (``swarmtag.errors.ResourceError``, see ``bootstrap_memory``).
    """
    check_instance("runs", runs, ConditionRuns, error=StatisticsError)
    check_options(
        n_resamples=n_resamples,
        seed=seed,
        confidence_level=confidence_level,
        curve_thresholds=curve_thresholds,
        curve_percentiles=curve_percentiles,
    )
    check_compiled(compiled)
    estimate = bootstrap_memory(
        n_resamples,
        conditions=1,
        width=len(runs.carrier),
        curve_points=len(curve_thresholds) + len(curve_percentiles),
    )
    check_memory(f"--resamples {n_resamples} over 1 condition", estimate)
    return _statistics(
        runs,
        n_resamples=n_resamples,
        seed=seed,
        confidence_level=confidence_level,
        curve_thresholds=curve_thresholds,
        curve_percentiles=curve_percentiles,
        chunk_elements=_chunk_elements,
        compiled=compiled,
    )


def _statistics(
    runs: ConditionRuns,
    *,
    n_resamples: int,
    seed: int,
    confidence_level: float,
    curve_thresholds: Sequence[int] = CURVE_THRESHOLDS,
    curve_percentiles: Sequence[float] = LATENCY_PERCENTILES,
    chunk_elements: int = CHUNK_ELEMENTS,
    compiled: bool | None = None,
) -> ConditionStatistics:
    """``condition_statistics`` without its checks: for callers that checked (``summarize``).

    ``compiled``: run the compiled kernels (``swarmtag.analysis._kernels``),
    or not; ``None`` decides from this condition's work alone.
    """
    values = run_values(runs, curve_thresholds=curve_thresholds)
    kpis = condition_kpis(values)
    replicates, pa_replicates, latency_replicates = _replicates(
        values,
        n_resamples=n_resamples,
        seed=seed,
        curve_thresholds=curve_thresholds,
        curve_percentiles=curve_percentiles,
        chunk_elements=chunk_elements,
        km=kpis.km_p95_latency is not None,  # else undefined outright: no value computed
        compiled=compiled,
    )
    estimates = {
        metric: Estimate(
            value=kpis.value(metric),
            confidence_interval=percentile_interval(
                replicates[metric], confidence_level=confidence_level
            ),
            bootstrap_distribution=replicates[metric],
        )
        for metric in METRICS + OPTIONAL_METRICS
    }
    pooled = values.latencies.values
    latency_values = (
        np.percentile(pooled, list(curve_percentiles))
        if pooled.size
        else np.full(len(curve_percentiles), np.nan)
    )
    return ConditionStatistics(
        condition=runs.condition,
        kpis=kpis,
        values=values,
        n_resamples=n_resamples,
        seed=seed,
        confidence_level=confidence_level,
        p95_latency=estimates["p95_latency"],
        mean_latency=estimates["mean_latency"],
        throughput=estimates["throughput"],
        pa=estimates["pa"],
        deliveries_per_run=estimates["deliveries_per_run"],
        pa_curve=Curve.from_replicates(
            curve_thresholds,
            np.mean(values.pa_curve(curve_thresholds), axis=0),
            pa_replicates,
            confidence_level,
        ),
        latency_curve=Curve.from_replicates(
            curve_percentiles, latency_values, latency_replicates, confidence_level
        ),
        p95_latency_censored=estimates["p95_latency_censored"],
        mean_latency_censored=estimates["mean_latency_censored"],
        km_p95_latency=estimates["km_p95_latency"],
        pa_at_delivery=estimates["pa_at_delivery"] if kpis.has_pa_at_delivery else None,
    )
