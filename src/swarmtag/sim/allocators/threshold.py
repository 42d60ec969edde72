"""Response threshold (Bonabeau, Theraulaz and Deneubourg 1996), one decision per encounter.

A walker decides on each of its candidates this tick: it takes carrier
``c`` if its allocation-stream number is below ``T(s) = s^2 / (s^2 +
theta^2)``, ``s = u_c + 1`` (the urgency it heard plus one, so that an
urgency-0 carrier is still taken sometimes); one it does not take is
passed over for the cooldown (``timing.cooldown``, as after a timeout), so
that it is met again later, its stimulus perhaps grown. Among the carriers
it takes it fetches the nearest (the proximity score and tie rule).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from swarmtag.errors import SimulationError
from swarmtag.policy import Threshold, best_of, proximity_term
from swarmtag.sim.allocators.base import AllocatorChooser
from swarmtag.sim.builtin.decide import Selection
from swarmtag.sim.model.state import Int

__all__ = ["ThresholdChooser"]


class ThresholdChooser(AllocatorChooser):
    """The response-threshold choice step of one batch."""

    def __init__(self, policy: Threshold) -> None:
        self.policy = policy

    def __call__(self, selection: Selection) -> tuple[Int, NDArray[np.float64]]:
        """Take each candidate with probability T(s); the nearest taken; pass over the rest."""
        s, params, candidates = selection.s, selection.params, selection.available
        drawn = selection.inputs.allocation
        if drawn is None:
            msg = "threshold: the tick's inputs carry no allocation draws"
            raise SimulationError(msg)
        take = drawn[..., : params.carriers] < self.policy.take_up(s.known_urgency)
        taken = candidates & take
        s.blocked_until[candidates & ~take] = selection.t + params.cooldown_ticks
        choice = best_of(
            proximity_term(selection.distance),
            distance=selection.distance,
            marker=params.markers,
            available=taken,
        ).astype(np.int64)
        return choice, candidates.sum(axis=-1).astype(np.float64)
