"""What happened in a tick, and the long-format event table built from it (SPEC §8.1).

Event kinds (the ``kind`` column), in the order they can happen in a tick:

=================  ==========================================================
``breakdown``      a robot broke down; ``carrier`` is the one it held (stuck) or empty
``abandon``        a robot gave up its pursuit: it heard the target is no longer
                   AWAITING_PICKUP; ``value`` = the status it heard
``timeout``        a pursuit reached the timeout; the cool-down starts
``select``         a robot chose a carrier; ``value`` = the urgency it heard
``candidates``     with every ``select``: ``value`` = how many candidates the
                   robot chose among (the choice statistics of SPEC §4.2a)
``lift``           a robot lifted a carrier (tag -> PICKED_UP); ``value`` = urgency
``lift_refused``   a robot centred under a carrier could not lift it (another,
                   smaller-id robot lifted it this tick, or the tag refused the
                   write); ``value`` = the tag's status
``deliver``        a robot put a carrier down in the drop-off area (tag -> IDLE);
                   ``value`` = urgency
``reprioritise``   an operator write set a carrier's urgency; ``value`` = the new
                   urgency; ``robot`` is empty
``arrive``         a warehouse order was placed on a pick-up slot; ``value`` = its
                   urgency; ``robot`` is empty
``messages``       an allocator that talks (CBAA): ``value`` = the messages the
                   robot sent since its last ``messages`` event; ``carrier`` is
                   empty (``swarmtag.sim.allocators.cbaa``)
=================  ==========================================================

Rows are sorted by run, time, kind (the order above), robot, carrier, so a
run's rows do not depend on the batch it was computed in.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from enum import IntEnum

import numpy as np
from numpy.typing import NDArray

from swarmtag.io import MISSING_ID, EventTable
from swarmtag.sim.model.geometry import Float
from swarmtag.sim.model.state import Int

__all__ = ["CarrierEvent", "EventKind", "EventRecorder", "TickEvents"]


class EventKind(IntEnum):
    """Event kinds; the number is the order within a tick (the phase they happen in)."""

    BREAKDOWN = 1
    ABANDON = 2
    TIMEOUT = 3
    SELECT = 4
    CANDIDATES = 5
    LIFT = 6
    LIFT_REFUSED = 7
    DELIVER = 8
    REPRIORITISE = 9
    ARRIVE = 10
    MESSAGES = 11

    @property
    def label(self) -> str:
        """The name written in the ``kind`` column, e.g. ``lift_refused``."""
        return self.name.lower()


@dataclass(frozen=True, eq=False)
class RobotEvents:
    """Robots (``mask``, shape (R, N)) to which one kind of event happened this tick."""

    kind: EventKind
    mask: NDArray[np.bool_]
    carrier: Int
    value: Float


@dataclass(frozen=True)
class CarrierEvent:
    """An event of one carrier without a robot (an operator write) in batch row ``run``."""

    kind: EventKind
    run: int
    carrier: int
    value: float


@dataclass(eq=False)
class TickEvents:
    """The events of one tick, collected by the kernel phases in phase order."""

    entries: list[RobotEvents] = field(default_factory=list)
    carrier_entries: list[CarrierEvent] = field(default_factory=list)

    def add(self, kind: EventKind, mask: NDArray[np.bool_], carrier: Int, value: Float) -> None:
        """Record ``kind`` for the robots in ``mask`` (copies are kept)."""
        if mask.any():
            self.entries.append(RobotEvents(kind, mask.copy(), carrier.copy(), value.copy()))

    def add_carrier(self, kind: EventKind, run: int, carrier: int, value: float) -> None:
        """Record ``kind`` for ``carrier`` of batch row ``run`` (no robot)."""
        self.carrier_entries.append(CarrierEvent(kind, run, carrier, value))

    def masked(self, keep: NDArray[np.bool_]) -> TickEvents:
        """The same events restricted to the runs where ``keep`` (shape (R,)) is true."""
        return TickEvents(
            [
                RobotEvents(e.kind, e.mask & keep[:, None], e.carrier, e.value)
                for e in self.entries
                if (e.mask & keep[:, None]).any()
            ],
            [e for e in self.carrier_entries if keep[e.run]],
        )

    def count(self, kind: EventKind, runs: int) -> NDArray[np.int64]:
        """Events of ``kind`` per run this tick, for a batch of ``runs`` runs."""
        total = np.zeros(runs, dtype=np.int64)
        for entry in self.entries:
            if entry.kind is kind:
                total += entry.mask.sum(axis=1, dtype=np.int64)
        return total


_LABELS = np.array([""] + [kind.label for kind in EventKind], dtype=str)
"""The ``kind`` column's text, indexed by ``EventKind`` value."""
assert [int(kind) for kind in EventKind] == list(range(1, len(EventKind) + 1))


class EventRecorder:
    """Accumulates event rows tick by tick and builds the ``EventTable`` at the end."""

    def __init__(self) -> None:
        self._rows: list[tuple[Int, Int, Int, Int, Int, Float]] = []

    def add_tick(self, tick: int, events: TickEvents) -> None:
        """Rows for every event of ``tick``."""
        for entry in events.entries:
            runs, robots = np.nonzero(entry.mask)
            self._rows.append(
                (
                    runs,
                    np.full(runs.shape, tick, dtype=np.int64),
                    np.full(runs.shape, int(entry.kind), dtype=np.int64),
                    entry.carrier[runs, robots],
                    robots.astype(np.int64),
                    entry.value[runs, robots],
                )
            )
        for event in events.carrier_entries:
            self._rows.append(
                (
                    np.array([event.run]),
                    np.array([tick]),
                    np.array([int(event.kind)]),
                    np.array([event.carrier]),
                    np.array([MISSING_ID]),
                    np.array([event.value]),
                )
            )

    def add_rows(
        self,
        runs: Int,
        ticks: Int,
        kinds: Int,
        *,
        carriers: Int,
        robots: Int,
        values: Float,
    ) -> None:
        """Rows made elsewhere (a compiled kernel's buffers): batch rows, ticks, kinds, ..."""
        self._rows.append(
            (
                runs.astype(np.int64),
                ticks.astype(np.int64),
                kinds.astype(np.int64),
                carriers.astype(np.int64),
                robots.astype(np.int64),
                values.astype(np.float64),
            )
        )

    def table(
        self,
        *,
        condition: str,
        seed: int,
        run_ids: Int,
        time_scale: float = 1.0,
        time_unit: str = "tick",
    ) -> EventTable:
        """The sorted event table; ``run_ids`` maps batch positions to global run ids.

        Times are ticks times ``time_scale`` (1, or the tick in seconds when
        ``time_unit`` is ``"s"``).
        """
        if self._rows:
            runs, ticks, kinds, carriers, robots, values = (
                np.concatenate(column) for column in zip(*self._rows, strict=True)
            )
        else:
            runs = ticks = kinds = carriers = robots = np.zeros(0, dtype=np.int64)
            values = np.zeros(0)
        global_runs = run_ids[runs]
        order = np.lexsort((carriers, robots, kinds, ticks, global_runs))
        labels = _LABELS[kinds[order]]
        return EventTable(
            condition=np.full(order.shape, condition),
            seed=np.full(order.shape, seed, dtype=np.int64),
            run=global_runs[order],
            time=ticks[order].astype(np.float64) * time_scale,
            kind=labels if labels.size else np.zeros(0, dtype=str),
            carrier=carriers[order],
            robot=robots[order],
            value=values[order],
            time_unit=time_unit,
        )
