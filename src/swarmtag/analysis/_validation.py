"""The one place where options of the statistics functions are checked."""

from __future__ import annotations

from collections.abc import Sequence
from numbers import Integral, Real

from swarmtag._checks import check_sequence, show
from swarmtag.errors import StatisticsError

__all__ = ["check_compiled", "check_level", "check_options", "check_thresholds"]


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
        raise StatisticsError(f"n_resamples: {show(n_resamples)} is not a positive integer")
    if not _integer(seed, low=0):
        raise StatisticsError(f"seed: {show(seed)} is not an integer >= 0")
    check_level(confidence_level)
    check_thresholds("curve_thresholds", curve_thresholds)
    curve_percentiles = check_sequence(
        "curve_percentiles", curve_percentiles, error=StatisticsError
    )
    for q in curve_percentiles:
        if not _real(q, low=0, high=100):
            raise StatisticsError(f"curve_percentiles: {show(q)} is not a percentile in 0-100")


def check_thresholds(name: str, thresholds: object) -> tuple[int, ...]:
    """A sequence of integer percentages in 0-100 (PA thresholds), else ``StatisticsError``."""
    checked = []
    for p in check_sequence(name, thresholds, error=StatisticsError):
        if not _integer(p, low=0, high=100):
            raise StatisticsError(f"{name}: {show(p)} is not an integer percentage in 0-100")
        checked.append(int(p))
    return tuple(checked)


def check_level(confidence_level: object) -> float:
    """A confidence level strictly between 0 and 1, else ``StatisticsError``.

    >>> check_level(-1)
    Traceback (most recent call last):
    ...
    swarmtag.errors.StatisticsError: confidence_level: -1 is not a number strictly between 0 and 1
    """
    if not _real(confidence_level, low=0, high=1) or confidence_level in (0, 1):
        raise StatisticsError(
            f"confidence_level: {show(confidence_level)} is not a number strictly between 0 and 1"
        )
    return float(confidence_level)  # type: ignore[arg-type]  # a Real, checked above


def check_compiled(compiled: object) -> bool | None:
    """``compiled`` if it is ``True``, ``False`` or ``None`` (pick), else ``StatisticsError``."""
    if compiled is None or isinstance(compiled, bool):
        return compiled
    raise StatisticsError(f"compiled: {show(compiled)} is not true, false or None")
