"""Rules every controller of the published robot follows, shared by the built-in one and the tree.

The built-in vectorised controller (``swarmtag.sim.builtin``) and the
behaviour tree (``swarmtag.robot``) both import them from here, so that the
two cannot drift apart and neither imports the other.
"""

from __future__ import annotations

from typing import Final

import numpy as np
from numpy.typing import NDArray

__all__ = ["STUCK_PROGRESS", "away_from"]

Float = NDArray[np.float64]

STUCK_PROGRESS: Final = 0.25
"""A loaded robot that moved less than this fraction of its step counts a stuck tick."""


def away_from(direction: Float, push: Float) -> Float:
    """``direction`` reversed where it points against ``push`` (negative dot product).

    >>> away_from(np.array([[1.0, 0.0]]), np.array([[-0.01, 0.0]]))
    array([[-1., -0.]])
    """
    dot = direction[..., 0] * push[..., 0] + direction[..., 1] * push[..., 1]
    return np.where((dot < 0)[..., None], -direction, direction)
