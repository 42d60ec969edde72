"""Scheduled re-prioritisations as operator (WMS) writes: the last phase of ``step``.

The writes due at tick t come with the tick's inputs (``TickInputs.writes``;
``RandomSource`` hands out the scenario's schedule). For every run still
running, the carrier's tag is set up with its current state
(``TagModel.provision``), the run's operator signs ``Change(urgency=u)``
with its next counter (``WriteSigner``; the run's last counter is world
state, ``operator_counter``), and the tag applies the 20-byte
write exactly as a real tag would (MAC, target, counter, role rules). The
tag's resulting urgency goes back into the world state, and the urgency stops
growing. ``urgency0`` and ``order_time`` are not touched (SPEC §4.3). Writes
are rare, so a little Python per write is fine.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Final

import numpy as np

from swarmtag.sim.config.parts import Reprioritisation
from swarmtag.sim.model.events import EventKind, TickEvents
from swarmtag.sim.model.state import WorldState
from swarmtag.tag import Change, MemoryStore, Role, TagModel, TagState, TagStatus, WriteSigner
from swarmtag.tag.keys import derive_role_key

__all__ = ["OPERATOR_ID", "SIM_SITE_KEY", "operator_writes"]

SIM_SITE_KEY: Final = b"swarmtag-sim-key"
"""The site key of simulated tags (16 bytes; for simulation only, never for real tags)."""
OPERATOR_ID: Final = 0xFFFE
"""Writer id of the simulated warehouse management system."""


def operator_writes(
    s: WorldState, writes: Sequence[Reprioritisation], *, t: int, events: TickEvents
) -> None:
    """Apply the operator writes due at tick ``t`` to every run still running (in place)."""
    if not writes:
        return
    running = (s.ended_at < 0) | (s.ended_at == t)
    slot = t % s.adv_urgency.shape[1]
    for run in np.flatnonzero(running).tolist():
        signer = WriteSigner(
            writer=OPERATOR_ID,
            role=Role.OPERATOR,
            key=derive_role_key(SIM_SITE_KEY, Role.OPERATOR),
            counter=int(s.operator_counter[run]),
        )
        for event in writes:
            c = event.carrier
            tag = TagModel.provision(
                TagState(
                    urgency=int(s.urgency[run, c]),
                    status=TagStatus(int(s.status[run, c])),
                    destination=0,
                    marker=c,
                ),
                site_key=SIM_SITE_KEY,
                store=MemoryStore(),
            )
            result = tag.apply(signer.sign(c, Change(urgency=event.urgency)))
            s.urgency[run, c] = result.urgency
            s.w0[run, c] = np.nan
            s.adv_urgency[run, slot, c] = result.urgency
            events.add_carrier(EventKind.REPRIORITISE, run, c, float(result.urgency))
        s.operator_counter[run] = signer.counter
