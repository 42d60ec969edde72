"""When a tag advertises: at ``phase + k * interval`` on a grid of whole microseconds.

One schedule for every radio in the project: the simulator's radio channel
(``sim/world/sensing.py``, vectorised per tick) and the virtual radio of the tag
backends (``tag/backends/sim.py``, advert by advert) both count adverts with
these functions, so a tag with a given phase and interval is heard at the
same moments by both (``tests/tag/test_advertising.py`` checks it). Integer
arithmetic keeps the schedule exact: float times would drift over a long run.
"""

from __future__ import annotations

import math
from typing import TypeVar, overload

import numpy as np
from numpy.typing import NDArray

__all__ = ["advert_times", "adverts_sent", "microseconds", "phase_microseconds"]

_Int = TypeVar("_Int", int, NDArray[np.int64])


def microseconds(seconds: float) -> int:
    """``seconds`` on the microsecond grid (nearest whole microsecond)."""
    return round(seconds * 1e6)


@overload
def phase_microseconds(fraction: float, interval_us: int) -> int: ...
@overload
def phase_microseconds(fraction: NDArray[np.float64], interval_us: int) -> NDArray[np.int64]: ...
def phase_microseconds(
    fraction: float | NDArray[np.float64], interval_us: int
) -> int | NDArray[np.int64]:
    """A phase drawn as a fraction in [0, 1) of the interval, in whole microseconds (floor)."""
    if isinstance(fraction, np.ndarray):
        return np.floor(fraction * interval_us).astype(np.int64)
    return math.floor(fraction * interval_us)


def adverts_sent(phase_us: _Int, interval_us: int, after_us: int, until_us: int) -> _Int:
    """How many adverts a tag sends in ``(after_us, until_us]`` (elementwise for arrays).

    Adverts go out at ``phase_us + k * interval_us``; with ``0 <= phase_us <
    interval_us`` and ``after_us >= 0`` only ``k >= 0`` fall in the window.
    """
    sent: _Int = (until_us - phase_us) // interval_us - (after_us - phase_us) // interval_us
    return sent


def advert_times(phase_us: int, interval_us: int, after_us: int, until_us: int) -> list[int]:
    """The send times (microseconds) of one tag's adverts in ``(after_us, until_us]``."""
    first = (after_us - phase_us) // interval_us + 1
    return [
        phase_us + k * interval_us for k in range(first, (until_us - phase_us) // interval_us + 1)
    ]
