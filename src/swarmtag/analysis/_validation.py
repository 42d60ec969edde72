"""The one place where options of the statistics functions are checked."""

from __future__ import annotations

from collections.abc import Sequence
from numbers import Integral, Real

from swarmtag.errors import StatisticsError

__all__ = ["check_options"]


def _integer(value: object, *, low: int, high: int | None = None) -> bool:
    if isinstance(value, bool) or not isinstance(value, Integral):
        return False
    return low <= int(value) and (high is None or int(value) <= high)


def _real(value: object, *, low: float, high: float) -> bool:
    if isinstance(value, bool) or not isinstance(value, Real):
        return False
    return low <= float(value) <= high


def check_options(
    *,
    n_resamples: object,
    seed: object,
    confidence_level: object,
    curve_thresholds: Sequence[object] = (),
    curve_percentiles: Sequence[object] = (),
) -> None:
    """Refuse a bad resample count, seed, level or curve axis with a message naming it.

    Integers may be Python or numpy integers; ``bool`` is refused everywhere.
    """
    if not _integer(n_resamples, low=1):
        raise StatisticsError(f"n_resamples: {n_resamples!r} is not a positive integer")
    if not _integer(seed, low=0):
        raise StatisticsError(f"seed: {seed!r} is not an integer >= 0")
    if not _real(confidence_level, low=0, high=1) or confidence_level in (0, 1):
        raise StatisticsError(
            f"confidence_level: {confidence_level!r} is not a number strictly between 0 and 1"
        )
    for p in curve_thresholds:
        if not _integer(p, low=0, high=100):
            raise StatisticsError(f"curve_thresholds: {p!r} is not an integer percentage in 0-100")
    for q in curve_percentiles:
        if not _real(q, low=0, high=100):
            raise StatisticsError(f"curve_percentiles: {q!r} is not a percentile in 0-100")
