"""Event slots and buffers of the compiled kernel.

During a tick each robot has one slot per event kind (``EVENT_SLOTS``; a
robot has at most one event of each kind per tick), so robots can be handled
in any order or in parallel; ``flush_slots`` then appends the tick's events
to the run's buffer in robot and kind order. The event table is sorted by
(run, time, kind, robot, carrier) afterwards, so the order rows are appended
in never shows.
"""

from __future__ import annotations

from swarmtag.sim.fast._jit import inlined
from swarmtag.sim.fast._scratch import EVENT_SLOTS, Scratch

__all__ = ["emit", "flush_slots", "room_for_tick"]


@inlined
def emit(r: int, n: int, kind: int, carrier: int, value: float, x: Scratch) -> None:
    """Record event ``kind`` (1-8) of robot ``n`` in run ``r`` this tick."""
    x.slot_on[r, n, kind - 1] = True
    x.slot_carrier[r, n, kind - 1] = carrier
    x.slot_value[r, n, kind - 1] = value


@inlined
def room_for_tick(r: int, robots: int, x: Scratch) -> bool:
    """Whether run ``r``'s buffer can take every event one tick could make."""
    room: bool = x.event_count[r] + robots * EVENT_SLOTS <= x.event_tick.shape[1]
    return room


@inlined
def flush_slots(r: int, t: int, robots: int, x: Scratch) -> None:
    """Append the slots of tick ``t`` to run ``r``'s buffer and clear them."""
    row = x.event_count[r]
    for n in range(robots):
        for slot in range(EVENT_SLOTS):
            if not x.slot_on[r, n, slot]:
                continue
            x.slot_on[r, n, slot] = False
            x.event_tick[r, row] = t
            x.event_kind[r, row] = slot + 1
            x.event_robot[r, row] = n
            x.event_carrier[r, row] = x.slot_carrier[r, n, slot]
            x.event_value[r, row] = x.slot_value[r, n, slot]
            row += 1
    x.event_count[r] = row
