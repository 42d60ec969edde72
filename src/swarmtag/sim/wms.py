"""Scheduled re-prioritisations as operator (WMS) writes through the authenticated tag path.

At the end of the tick a ``Reprioritisation`` names, for every run still
running, the carrier's tag is set up with its current state
(``TagModel.provision``), the run's operator signs ``Change(urgency=u)``
with its next counter (``WriteSigner``), and the tag applies the 20-byte
write exactly as a real tag would (MAC, target, counter, role rules). The
tag's resulting urgency goes back into the world state, and the urgency stops
growing. ``urgency0`` and ``order_time`` are not touched (SPEC §4.3). Writes
are rare, so a little Python per write is fine.
"""

from __future__ import annotations

from collections import defaultdict
from collections.abc import Sequence
from dataclasses import replace
from typing import Final

import numpy as np

from swarmtag.sim.events import EventKind, EventRecorder
from swarmtag.sim.groups import Reprioritisation
from swarmtag.sim.state import WorldState
from swarmtag.tag import Change, MemoryStore, Role, TagModel, TagState, TagStatus, WriteSigner

__all__ = ["OPERATOR_ID", "SIM_SITE_KEY", "Operator"]

SIM_SITE_KEY: Final = b"swarmtag-sim-key"
"""The site key of simulated tags (16 bytes; for simulation only, never for real tags)."""
OPERATOR_ID: Final = 0xFFFE
"""Writer id of the simulated warehouse management system."""


class Operator:
    """The WMS of a batch: applies the scenario's scheduled writes to every running run."""

    def __init__(self, schedule: Sequence[Reprioritisation], runs: int) -> None:
        self._by_tick: dict[int, list[Reprioritisation]] = defaultdict(list)
        for event in schedule:
            self._by_tick[event.tick].append(event)
        self._signers = [
            WriteSigner(writer=OPERATOR_ID, role=Role.OPERATOR, key=SIM_SITE_KEY)
            for _ in range(runs)
        ]

    def apply(self, state: WorldState, recorder: EventRecorder | None = None) -> WorldState:
        """``state`` after this tick's scheduled writes (the same object if there are none)."""
        due = self._by_tick.get(state.tick)
        if not due:
            return state
        running = (state.ended_at < 0) | (state.ended_at == state.tick)
        urgency = state.urgency.copy()
        w0 = state.w0.copy()
        adv_urgency = state.adv_urgency.copy()
        slot = state.tick % state.adv_urgency.shape[1]
        for run in np.flatnonzero(running).tolist():
            for event in due:
                c = event.carrier
                tag = TagModel.provision(
                    TagState(
                        urgency=int(urgency[run, c]),
                        status=TagStatus(int(state.status[run, c])),
                        destination=0,
                        marker=c,
                    ),
                    site_key=SIM_SITE_KEY,
                    store=MemoryStore(),
                )
                message = self._signers[run].sign(c, Change(urgency=event.urgency))
                result = tag.apply(message)
                urgency[run, c] = result.urgency
                w0[run, c] = np.nan
                adv_urgency[run, slot, c] = result.urgency
                if recorder is not None:
                    recorder.add_carrier_event(
                        state.tick, EventKind.REPRIORITISE, run, c, float(result.urgency)
                    )
        return replace(state, urgency=urgency, w0=w0, adv_urgency=adv_urgency)
