"""The built-in controller: every robot of a batch decides at once, in numpy (the default).

Its three steps are ``decide.decide``, ``docking.arrive`` and
``docking.carry``; its memory is the state's robot fields
(``control.MEMORY_FIELDS``). The behaviour tree of ``swarmtag.robot`` is
the per-robot implementation of the same rules.
"""

from __future__ import annotations

from typing import Final

from swarmtag.sim.builtin.decide import decide
from swarmtag.sim.builtin.docking import arrive, carry
from swarmtag.sim.control.interface import Arrivals, Carrying, Controller, LiftAnswers
from swarmtag.sim.model.events import TickEvents
from swarmtag.sim.model.params import Params
from swarmtag.sim.model.randomness import TickInputs
from swarmtag.sim.model.state import WorldState
from swarmtag.sim.world.sensing import Senses

__all__ = ["BUILTIN", "BuiltinController"]


class BuiltinController:
    """The vectorised controller of SPEC §3.2 (stateless: its memory is in the world state)."""

    name = "builtin"

    def decide(
        self,
        before: WorldState,
        s: WorldState,
        *,
        senses: Senses,
        inputs: TickInputs,
        params: Params,
        t: int,
        events: TickEvents,
    ) -> None:
        """See ``swarmtag.sim.builtin.decide``."""
        decide(before, s, senses=senses, inputs=inputs, params=params, t=t, events=events)

    def arrive(self, before: WorldState, s: WorldState, *, params: Params, t: int) -> Arrivals:
        """See ``swarmtag.sim.builtin.docking.arrive``."""
        return arrive(before, s, params=params, t=t)

    def carry(self, s: WorldState, answers: LiftAnswers, *, params: Params, t: int) -> Carrying:
        """See ``swarmtag.sim.builtin.docking.carry``."""
        return carry(s, answers, params=params, t=t)


BUILTIN: Final[Controller] = BuiltinController()
"""The default controller."""
