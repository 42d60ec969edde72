"""Score rules of one's own, to run beside the built-in conditions (docs/policy.md).

    swarmtag policy check examples/rules.py:urgency_first
    swarmtag simulate --condition proximity --policy-file examples/rules.py:urgency_first

A rule scores each candidate from its own values: larger wins, ties go to the
nearer carrier, then the smaller marker id.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray


def urgency_first(
    urgency: NDArray[np.float64], distance: NDArray[np.float64]
) -> NDArray[np.float64]:
    """The most urgent carrier first, the nearer among equals (ranks as the built-in edf)."""
    return urgency * 100.0 - np.minimum(distance, 99.0)


def oldest_first(
    urgency: NDArray[np.float64], distance: NDArray[np.float64], age: NDArray[np.float64]
) -> NDArray[np.float64]:
    """The warehouse FIFO heuristic: the carrier that has waited longest (``age``, seconds)."""
    del urgency, distance
    return age
