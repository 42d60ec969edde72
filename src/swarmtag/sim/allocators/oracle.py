"""Central assignment with global knowledge (Kuhn 1955; scipy's ``linear_sum_assignment``).

Every tick in which robots are idle (walking, not seeking) the central
system assigns them to the carriers waiting for a robot (status
AWAITING_PICKUP as the tags hold it, a free face, no robot on its way to
it, not cooling down for that robot), at most one each: as many robots
as can be served, and among those assignments the largest summed urgency
score ``u_c * (alpha + u_d)`` of the tags' true urgencies and the true
distances; among equal totals, the smaller total distance.
Robots already under way keep their carriers (re-solved whenever one
becomes free). Pursuits are checked against the tags' true status: the
system tells its robots when a carrier is gone.
"""

from __future__ import annotations

import importlib
from typing import Final

import numpy as np
from numpy.typing import NDArray

from swarmtag.policy import Oracle
from swarmtag.sim.allocators.base import AllocatorChooser
from swarmtag.sim.builtin.decide import Selection
from swarmtag.sim.model.geometry import Float
from swarmtag.sim.model.indexing import PURSUIT_MODES, in_modes
from swarmtag.sim.model.state import Int
from swarmtag.tag import TagStatus

__all__ = ["OracleChooser", "assign"]

_AWAITING = int(TagStatus.AWAITING_PICKUP)
TIE_PER_METRE: Final = 1e-9
"""Score given up per metre of distance: among equal score totals, the shorter total wins."""
_FORBIDDEN: Final = 1e12
"""The cost of a pair that may not be assigned (larger than any total of allowed ones)."""


def assign(score: Float, distance: Float, allowed: NDArray[np.bool_]) -> Int:
    """The carrier each robot gets (-1 none): as many allowed pairs as can be made, best total.

    ``score``, ``distance`` and ``allowed`` are (robots, carriers). Each
    robot gets at most one carrier and each carrier at most one robot;
    among the assignments with the most pairs (every idle robot served
    that can be), the total ``score - TIE_PER_METRE * distance`` is
    largest; only allowed pairs are made.

    >>> assign(np.array([[9.0, 1.0], [8.0, 2.0]]), np.zeros((2, 2)), np.ones((2, 2), bool))
    array([0, 1])
    """
    robots = allowed.shape[0]
    choice = np.full(robots, -1, dtype=np.int64)
    if not allowed.any():
        return choice
    optimize = importlib.import_module("scipy.optimize")  # ships no type stubs
    # 1. how many pairs can be made: a largest matching of the allowed pairs
    rows, cols = optimize.linear_sum_assignment(np.where(allowed, -1.0, 0.0))
    pairs = int(allowed[rows, cols].sum())
    # 2. the best total among matchings of that size: robots left over take a dummy column
    cost = np.where(allowed, TIE_PER_METRE * distance - score, _FORBIDDEN)
    dummies = np.zeros((robots, robots - pairs))
    rows, cols = optimize.linear_sum_assignment(np.hstack((cost, dummies)))
    real = cols < allowed.shape[1]
    keep = real.copy()
    keep[real] = allowed[rows[real], cols[real]]
    choice[rows[keep]] = cols[keep]
    return choice


class OracleChooser(AllocatorChooser):
    """The central assignment of one batch."""

    global_knowledge = True

    def __init__(self, policy: Oracle) -> None:
        self.policy = policy

    def __call__(self, selection: Selection) -> tuple[Int, NDArray[np.float64]]:
        """Assign the idle robots of every run to its waiting carriers."""
        s, t = selection.s, selection.t
        idle = selection.walkers & (s.seek < 0)
        pursuing = in_modes(s.mode, PURSUIT_MODES)
        runs, robots = idle.shape
        claimed = np.zeros(s.status.shape, dtype=bool)
        rows, who = np.nonzero(pursuing)
        claimed[rows, s.target[rows, who]] = True
        waiting = (s.status == _AWAITING) & s.present & s.free_face.any(axis=-1) & ~claimed
        allowed = idle[..., None] & waiting[:, None, :] & (s.blocked_until <= t)
        choice = np.full((runs, robots), -1, dtype=np.int64)
        offset = s.robot_pos[:, :, None, :] - s.carrier_pos[:, None, :, :]
        distance = np.sqrt(offset[..., 0] ** 2 + offset[..., 1] ** 2)
        score = self.policy.score(s.urgency[:, None, :].astype(np.float64), distance)
        for run in np.flatnonzero(allowed.any(axis=(1, 2))):
            choice[run] = assign(score[run], distance[run], allowed[run])
        return choice, allowed.sum(axis=-1).astype(np.float64)
