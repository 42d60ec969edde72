"""Differences between a condition and the baseline (SPEC §5.1): bootstrap CI and two tests.

``diff = condition - baseline``. Its bootstrap values pair the two
conditions' own bootstrap values by resample index; as the two come from
independent generators, this is exactly resampling the two conditions' runs
independently. The two-sided bootstrap p-value is
``min(1, 2 * min(#(diff* <= 0), #(diff* >= 0)) / B)`` over the resamples in
which both figures are defined. The second test is Mann-Whitney U (two-sided,
scipy's defaults) on the per-run values; runs without a value are left out,
and the p-value is ``None`` when either side has no value at all, and for the
Kaplan-Meier P95 (which has no per-run value).

A comparison with fewer than ``MIN_RUNS`` runs on either side is
**underpowered**: the bootstrap over so few whole runs gives intervals too
narrow and p-values that reach 0, while the exact two-sided Mann-Whitney
test cannot go below ``smallest_mann_whitney_p(n1, n2) = 2 / C(n1 + n2,
n1)`` (0.33 at 2 runs each, 0.1 at 3, 1.1e-5 at 10): Mann-Whitney is then
the reference, and every output says "underpowered".

Every comparison also says whether the two conditions left different shares
of their carriers undelivered (``undelivered_differs``): then delivered-only
latency compares different sets of carriers and is biased, and the censored
companions are the ones to read.
"""

from __future__ import annotations

import importlib
import math
from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager
from contextvars import ContextVar
from dataclasses import dataclass
from typing import Final, TypeAlias

import numpy as np
from numpy.typing import ArrayLike, NDArray

from swarmtag._checks import check_array, check_instance, check_text
from swarmtag.analysis.bootstrap import (
    ConditionStatistics,
    ConfidenceInterval,
    percentile_interval,
)
from swarmtag.analysis.kpis import ConditionKPIs
from swarmtag.errors import StatisticsError

__all__ = [
    "MIN_RUNS",
    "Comparison",
    "Samples",
    "bootstrap_p_value",
    "compare",
    "compare_all",
    "mann_whitney_by",
    "mann_whitney_p",
    "mann_whitney_ps",
    "smallest_mann_whitney_p",
    "undelivered_differs",
]

MIN_RUNS: Final = 10
"""Fewer runs per condition than this make a comparison underpowered (module docstring)."""


def smallest_mann_whitney_p(first: int, second: int) -> float:
    """The smallest two-sided p the exact Mann-Whitney test gives for samples of these sizes.

    ``2 / C(n1 + n2, n1)``, at most 1: the p of two samples that do not overlap.

    >>> smallest_mann_whitney_p(2, 2), round(smallest_mann_whitney_p(10, 10), 7)
    (0.3333333333333333, 1.08e-05)
    """
    if first < 1 or second < 1:
        return 1.0
    return min(1.0, 2 / math.comb(first + second, first))


def bootstrap_p_value(differences: ArrayLike) -> float | None:
    """Two-sided p-value of a bootstrap distribution of differences; NaN values left out.

    >>> bootstrap_p_value([1.0, 2.0, -1.0, 3.0])
    0.5
    >>> bootstrap_p_value([0.0, 0.0])
    1.0
    >>> bootstrap_p_value([np.nan]) is None
    True
    """
    values = check_array("differences", differences, nan=True, error=StatisticsError)
    defined = values[~np.isnan(values)]
    if defined.size == 0:
        return None
    below = int(np.count_nonzero(defined <= 0))
    above = int(np.count_nonzero(defined >= 0))
    return min(1.0, 2 * min(below, above) / int(defined.size))


def mann_whitney_p(x: ArrayLike | None, y: ArrayLike | None) -> float | None:
    """Two-sided Mann-Whitney U p-value (scipy's defaults), NaN values left out.

    ``None`` when either sample is ``None`` or has no value.

    >>> mann_whitney_p([1.0, 2.0, 3.0], [1.0, 2.0, 3.0])
    1.0
    >>> mann_whitney_p([1.0], [np.nan]) is None
    True
    """
    return _mann_whitney_ps([(x, y)])[0]


_EXACT_UP_TO: Final = 8
"""scipy's default method tests a sample this small exactly unless ties occur anywhere in the
call; from one sample larger, always asymptotically: then a call of many pairs is many calls."""


def _samples(
    x: ArrayLike | None, y: ArrayLike | None
) -> tuple[NDArray[np.float64], NDArray[np.float64]] | None:
    """The two samples ``mann_whitney_p`` tests (NaN left out), or None where there is no test."""
    if x is None or y is None:  # a metric without per-run values (the KM P95)
        return None
    first = check_array("x", x, nan=True, error=StatisticsError)
    second = check_array("y", y, nan=True, error=StatisticsError)
    first = first[~np.isnan(first)]
    second = second[~np.isnan(second)]
    if first.size == 0 or second.size == 0:
        return None
    return first, second


Samples: TypeAlias = list[tuple[NDArray[np.float64], NDArray[np.float64]] | None]
"""The tested samples of each pair (no NaN), or None where a pair has no test."""

_TESTER: ContextVar[Callable[[Samples], list[float | None]] | None] = ContextVar(
    "mann_whitney_tester", default=None
)


@contextmanager
def mann_whitney_by(tester: Callable[[Samples], list[float | None]]) -> Iterator[None]:
    """Within this block, ``tester`` computes the Mann-Whitney p-values: ``mann_whitney_ps``.

    The CLI hands them to a process that imported scipy.stats while the
    command started (``swarmtag.cli._testing``); the numbers are the same.
    The tester is this context's: threads started inside compute their own.
    """
    token = _TESTER.set(tester)
    try:
        yield
    finally:
        _TESTER.reset(token)


def _mann_whitney_ps(
    pairs: Sequence[tuple[ArrayLike | None, ArrayLike | None]],
) -> list[float | None]:
    """``mann_whitney_p`` of each pair: ``mann_whitney_ps``, or ``mann_whitney_by``'s tester."""
    samples = [_samples(x, y) for x, y in pairs]
    tester = _TESTER.get()
    if tester is None or all(tested is None for tested in samples):
        return mann_whitney_ps(samples)
    return tester(samples)


def mann_whitney_ps(samples: Samples) -> list[float | None]:
    """The p-value of each pair of ``samples``: pairs of one size in one scipy call.

    Pairs whose samples have the same sizes, both larger than ``_EXACT_UP_TO``, go
    to one call along ``axis=1`` (scipy's per-pair arithmetic, the same bits);
    smaller ones one by one, as ties in one pair would change another's method.
    """
    ps: list[float | None] = [None] * len(samples)
    sizes: dict[tuple[int, int], list[int]] = {}
    for index, tested in enumerate(samples):
        if tested is not None:
            sizes.setdefault((tested[0].size, tested[1].size), []).append(index)
    if not sizes:
        return ps
    # scipy.stats takes a while to import (and ships no stubs): load it when a test runs.
    stats = importlib.import_module("scipy.stats")
    for (first, second), members in sizes.items():
        chosen = [tested for index in members if (tested := samples[index]) is not None]
        if min(first, second) > _EXACT_UP_TO:
            x = np.stack([pair[0] for pair in chosen])
            y = np.stack([pair[1] for pair in chosen])
            values = stats.mannwhitneyu(x, y, alternative="two-sided", axis=1).pvalue
        else:
            values = [stats.mannwhitneyu(*pair, alternative="two-sided").pvalue for pair in chosen]
        for index, value in zip(members, values, strict=True):
            ps[index] = float(value)
    return ps


@dataclass(frozen=True, eq=False)
class Comparison:
    """One metric of one condition against the baseline: difference, CI and two p-values."""

    condition: str
    baseline: str
    metric: str
    diff: float | None
    confidence_interval: ConfidenceInterval
    p_bootstrap: float | None
    p_mannwhitney: float | None
    bootstrap_distribution: NDArray[np.float64]
    """Bootstrap values of the difference; NaN where either figure was undefined."""
    undelivered: tuple[int, int]
    """Undelivered carriers of the condition and of the baseline."""
    undelivered_differs: bool
    """Whether the two left different shares of their carriers undelivered."""
    runs: tuple[int, int] = (0, 0)
    """Runs of the condition and of the baseline."""

    @property
    def underpowered(self) -> bool:
        """Fewer than ``MIN_RUNS`` runs on either side: read Mann-Whitney, not the bootstrap."""
        return min(self.runs) < MIN_RUNS

    @property
    def smallest_p(self) -> float:
        """The smallest p the exact Mann-Whitney test could give with these runs."""
        return smallest_mann_whitney_p(*self.runs)


def undelivered_differs(condition: ConditionKPIs, baseline: ConditionKPIs) -> bool:
    """Whether the undelivered shares differ: ``u_c / n_c != u_b / n_b``, in exact integers.

    With the same number of carriers on both sides, whether the counts differ.
    """
    check_instance("condition", condition, ConditionKPIs, error=StatisticsError)
    check_instance("baseline", baseline, ConditionKPIs, error=StatisticsError)
    return condition.undelivered * baseline.carriers != baseline.undelivered * condition.carriers


def compare(
    condition: ConditionStatistics, baseline: ConditionStatistics, metric: str
) -> Comparison:
    """Compare ``condition`` with ``baseline`` on ``metric`` (one both of them have)."""
    check_instance("condition", condition, ConditionStatistics, error=StatisticsError)
    check_instance("baseline", baseline, ConditionStatistics, error=StatisticsError)
    check_text("metric", metric, error=StatisticsError)
    _check_alike(condition, baseline)
    condition.estimate(metric), baseline.estimate(metric)  # refuse an unknown metric first
    runs = (condition.values.per_run(metric), baseline.values.per_run(metric))
    return _compare(condition, baseline, metric, mann_whitney_p(*runs))


def _check_alike(condition: ConditionStatistics, baseline: ConditionStatistics) -> None:
    """Refuse two conditions bootstrapped with other resamples or confidence levels."""
    if condition.n_resamples != baseline.n_resamples:
        raise StatisticsError(
            f"{condition.condition} has {condition.n_resamples} resamples but the baseline "
            f"{baseline.condition} has {baseline.n_resamples}; compute both alike"
        )
    if condition.confidence_level != baseline.confidence_level:
        raise StatisticsError("the two conditions were computed at different confidence levels")


def _compare(
    condition: ConditionStatistics,
    baseline: ConditionStatistics,
    metric: str,
    p_mannwhitney: float | None,
) -> Comparison:
    """``compare``, its Mann-Whitney p-value given."""
    mine, theirs = condition.estimate(metric), baseline.estimate(metric)
    differences = mine.bootstrap_distribution - theirs.bootstrap_distribution
    differences.flags.writeable = False
    diff = None if mine.value is None or theirs.value is None else mine.value - theirs.value
    return Comparison(
        condition=condition.condition,
        baseline=baseline.condition,
        metric=metric,
        diff=diff,
        confidence_interval=percentile_interval(
            differences, confidence_level=condition.confidence_level
        ),
        p_bootstrap=bootstrap_p_value(differences),
        p_mannwhitney=p_mannwhitney,
        bootstrap_distribution=differences,
        undelivered=(condition.kpis.undelivered, baseline.kpis.undelivered),
        undelivered_differs=undelivered_differs(condition.kpis, baseline.kpis),
        runs=(condition.kpis.runs, baseline.kpis.runs),
    )


def compare_all(
    condition: ConditionStatistics, baseline: ConditionStatistics
) -> tuple[Comparison, ...]:
    """``compare`` for every metric both have, in the order of ``METRICS`` (then optional ones).

    The Mann-Whitney tests of all metrics are batched (``_mann_whitney_ps``).
    """
    check_instance("condition", condition, ConditionStatistics, error=StatisticsError)
    check_instance("baseline", baseline, ConditionStatistics, error=StatisticsError)
    _check_alike(condition, baseline)
    metrics = [metric for metric in condition.metrics if metric in baseline.metrics]
    ps = _mann_whitney_ps(
        [(condition.values.per_run(metric), baseline.values.per_run(metric)) for metric in metrics]
    )
    return tuple(
        _compare(condition, baseline, metric, p) for metric, p in zip(metrics, ps, strict=True)
    )
