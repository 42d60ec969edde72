"""What every allocator's choice step shares: hooks around the built-in decisions."""

from __future__ import annotations

from abc import ABC, abstractmethod

import numpy as np
from numpy.typing import NDArray

from swarmtag.sim.builtin.decide import Selection
from swarmtag.sim.model.events import TickEvents
from swarmtag.sim.model.params import Params
from swarmtag.sim.model.randomness import TickInputs
from swarmtag.sim.model.state import Int, WorldState

__all__ = ["AllocatorChooser"]


class AllocatorChooser(ABC):
    """An allocator's choice step (``decide.Chooser``) with hooks before and after ``decide``.

    Subclasses implement ``__call__``; ``prepare`` (before the built-in
    decisions: messages, dropped tasks) and ``settle`` (after them: what
    the robots learnt this tick) do nothing unless overridden.
    """

    global_knowledge = False

    @abstractmethod
    def __call__(self, selection: Selection) -> tuple[Int, NDArray[np.float64]]:
        """Each robot's choice (R, N), -1 none, and its candidate count."""

    def prepare(
        self,
        before: WorldState,
        s: WorldState,
        *,
        inputs: TickInputs,
        params: Params,
        t: int,
        events: TickEvents,
    ) -> None:
        """Before the built-in decisions of tick ``t``."""
        del before, s, inputs, params, t, events

    def settle(
        self, before: WorldState, s: WorldState, *, params: Params, t: int, events: TickEvents
    ) -> None:
        """After the decisions of tick ``t``."""
        del before, s, params, t, events
