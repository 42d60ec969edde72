"""Adaptive alpha (this project's): each robot weighs urgency by what contention taught it.

Each robot starts with ``alpha = ADAPTIVE_START`` (0.7, the published
policy's) and scores its candidates ``u_c * (alpha_r + u_d)``. When it
loses a race (it gives up a pursuit because it heard its carrier is no
longer awaiting a robot: another took it), urgency led it where others go
too, so its alpha falls: ``alpha_r <- alpha_r * (1 - gain)`` (at least
``ADAPTIVE_FLOOR``). When it lifts a carrier, its alpha is drawn back:
``alpha_r <- alpha_r + gain * (ADAPTIVE_START - alpha_r)``. The state
lives in the batch's controller.
"""

from __future__ import annotations

from typing import Final

import numpy as np
from numpy.typing import NDArray

from swarmtag.policy import ADAPTIVE_START, Adaptive, best_of, proximity_term
from swarmtag.sim.allocators.base import AllocatorChooser
from swarmtag.sim.builtin.decide import Selection
from swarmtag.sim.model.events import TickEvents
from swarmtag.sim.model.indexing import PURSUIT_MODES, in_modes, own
from swarmtag.sim.model.params import Params
from swarmtag.sim.model.state import Int, Mode, WorldState
from swarmtag.tag import TagStatus

__all__ = ["ADAPTIVE_FLOOR", "AdaptiveChooser"]

ADAPTIVE_FLOOR: Final = 0.01
"""The least alpha a robot comes to (urgency then only breaks near-ties of nearness)."""
_AWAITING = int(TagStatus.AWAITING_PICKUP)


class AdaptiveChooser(AllocatorChooser):
    """The adaptive-alpha choice step of one batch: each robot's alpha (R, N)."""

    def __init__(self, policy: Adaptive) -> None:
        self.policy = policy
        self.alpha: NDArray[np.float64] | None = None
        self._lifting: NDArray[np.bool_] | None = None

    def _alphas(self, s: WorldState) -> NDArray[np.float64]:
        if self.alpha is None:
            self.alpha = np.full(s.mode.shape, ADAPTIVE_START)
        return self.alpha

    def __call__(self, selection: Selection) -> tuple[Int, NDArray[np.float64]]:
        """The urgency score with each robot's alpha, the built-in tie rule."""
        s = selection.s
        alpha = self._alphas(s)
        scores = s.known_urgency * (alpha[..., None] + proximity_term(selection.distance))
        choice = best_of(
            scores,
            distance=selection.distance,
            marker=selection.params.markers,
            available=selection.available,
        ).astype(np.int64)
        return choice, selection.available.sum(axis=-1).astype(np.float64)

    def settle(
        self, before: WorldState, s: WorldState, *, params: Params, t: int, events: TickEvents
    ) -> None:
        """Lower the alpha of robots that lost a race this tick; draw back those that lift."""
        del params, t, events
        alpha = self._alphas(s)
        was = in_modes(before.mode, PURSUIT_MODES)
        gave_up = was & (s.mode == int(Mode.WALK))
        lost = gave_up & (own(s.known_status, before.target) != _AWAITING)
        gain = self.policy.gain
        alpha[lost] = np.maximum(ADAPTIVE_FLOOR, alpha[lost] * (1.0 - gain))
        lifting = before.mode == int(Mode.LIFT)  # set by the last tick's carry step
        lifted = lifting if self._lifting is None else lifting & ~self._lifting
        self._lifting = lifting
        alpha[lifted] += gain * (ADAPTIVE_START - alpha[lifted])
