"""Curves with bootstrap bands: PA against threshold, pooled latency against percentile."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from fractions import Fraction
from typing import Final

import numpy as np
from numpy.typing import NDArray

__all__ = ["LATENCY_PERCENTILES", "Curve", "band", "interval_percentiles"]

LATENCY_PERCENTILES: Final = tuple(range(0, 101, 5))
"""Percentiles of the latency curve: 0 (shortest), 5, ..., 100 (longest)."""


def interval_percentiles(confidence_level: float) -> tuple[float, float]:
    """The percentiles bounding a central interval, computed exactly: 0.95 gives (2.5, 97.5).

    >>> interval_percentiles(0.95)
    (2.5, 97.5)
    """
    tail = (1 - Fraction(str(confidence_level))) / 2 * 100
    return float(tail), float(100 - tail)


def band(
    replicates: NDArray[np.float64], confidence_level: float
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Percentile interval of each column of ``(B, K)`` replicates, leaving out NaN ones.

    A column without any defined replicate gets NaN bounds.
    """
    low_q, high_q = interval_percentiles(confidence_level)
    low = np.full(replicates.shape[1], np.nan)
    high = np.full(replicates.shape[1], np.nan)
    for column in range(replicates.shape[1]):
        defined = replicates[:, column][~np.isnan(replicates[:, column])]
        if defined.size:
            low[column], high[column] = np.percentile(defined, [low_q, high_q])
    return low, high


@dataclass(frozen=True, eq=False)
class Curve:
    """A curve with a bootstrap band; NaN where undefined (e.g. latency without deliveries).

    ``x`` is the threshold (PA curve) or the percentile (latency curve).
    """

    x: NDArray[np.float64]
    value: NDArray[np.float64]
    low: NDArray[np.float64]
    high: NDArray[np.float64]

    @classmethod
    def from_replicates(
        cls,
        x: Sequence[float],
        value: NDArray[np.float64],
        replicates: NDArray[np.float64],
        confidence_level: float,
    ) -> Curve:
        """Point values plus the percentile band of their bootstrap replicates."""
        low, high = band(replicates, confidence_level)
        arrays = [np.asarray(x, dtype=np.float64), np.asarray(value, dtype=np.float64), low, high]
        for array in arrays:
            array.flags.writeable = False
        return cls(x=arrays[0], value=arrays[1], low=arrays[2], high=arrays[3])
