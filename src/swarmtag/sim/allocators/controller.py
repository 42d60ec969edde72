"""The allocating controller: the built-in controller with an allocator's choice step."""

from __future__ import annotations

from swarmtag.errors import ConfigError
from swarmtag.policy import Adaptive, Allocator, Cbaa, ClaimFirst, Oracle, Threshold
from swarmtag.sim.allocators.adaptive import AdaptiveChooser
from swarmtag.sim.allocators.base import AllocatorChooser
from swarmtag.sim.allocators.cbaa import CbaaChooser
from swarmtag.sim.allocators.claim import ClaimChooser
from swarmtag.sim.allocators.oracle import OracleChooser
from swarmtag.sim.allocators.threshold import ThresholdChooser
from swarmtag.sim.builtin.decide import decide
from swarmtag.sim.builtin.docking import arrive, carry
from swarmtag.sim.control.interface import Arrivals, Carrying, LiftAnswers
from swarmtag.sim.model.events import TickEvents
from swarmtag.sim.model.params import Params
from swarmtag.sim.model.randomness import TickInputs
from swarmtag.sim.model.state import WorldState
from swarmtag.sim.world.sensing import Senses

__all__ = ["AllocatingController", "allocating_controller"]


class AllocatingController:
    """The built-in controller's three steps, with ``chooser`` choosing (one batch's)."""

    name = "builtin"

    def __init__(self, chooser: AllocatorChooser) -> None:
        self.chooser = chooser

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
        """The allocator's preparation, the built-in decisions with its choice, its bookkeeping."""
        self.chooser.prepare(before, s, inputs=inputs, params=params, t=t, events=events)
        decide(
            before, s, senses=senses, inputs=inputs, params=params, t=t, events=events,
            chooser=self.chooser,
        )  # fmt: skip
        self.chooser.settle(before, s, params=params, t=t, events=events)

    def arrive(self, before: WorldState, s: WorldState, *, params: Params, t: int) -> Arrivals:
        """The built-in ``arrive``."""
        return arrive(before, s, params=params, t=t)

    def carry(self, s: WorldState, answers: LiftAnswers, *, params: Params, t: int) -> Carrying:
        """The built-in ``carry``."""
        return carry(s, answers, params=params, t=t)


def allocating_controller(policy: Allocator) -> AllocatingController:
    """A fresh controller running ``policy`` (one batch's: it keeps the allocator's state)."""
    chooser: AllocatorChooser
    if isinstance(policy, Threshold):
        chooser = ThresholdChooser(policy)
    elif isinstance(policy, Oracle):
        chooser = OracleChooser(policy)
    elif isinstance(policy, Adaptive):
        chooser = AdaptiveChooser(policy)
    elif isinstance(policy, Cbaa):
        chooser = CbaaChooser(policy)
    elif isinstance(policy, ClaimFirst):
        chooser = ClaimChooser(policy)
    else:
        msg = f"allocator {policy.name!r} has no controller in this version"
        raise ConfigError(msg)
    return AllocatingController(chooser)
