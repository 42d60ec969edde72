"""Warehouse orders placed as they fall due, compiled: ``orders.place_orders`` for one run.

Slots are taken in ascending order and orders in order number, as in the
reference; the ARRIVE rows go straight into the run's event buffer (they
have no robot, so no robot slot).
"""

from __future__ import annotations

import math

from swarmtag.sim.fast._docking import free_faces_run
from swarmtag.sim.fast._geometry import contact
from swarmtag.sim.fast._index import index_obstacles
from swarmtag.sim.fast._jit import inlined
from swarmtag.sim.fast._layout import Constants, Scratch, World

__all__ = ["place_orders_run"]

_LIFT, _RELEASE, _BROKEN = 4, 6, 7
_ARRIVE = 10
"""``EventKind.ARRIVE``."""


@inlined
def _robot_on(r: int, sx: float, sy: float, w: World, k: Constants) -> bool:
    """Whether a carrier set down at (sx, sy) would overlap a robot (``orders._robots_on``)."""
    for n in range(k.robots):
        mode = w.mode[r, n]
        loaded = (_LIFT <= mode <= _RELEASE or mode == _BROKEN) and w.target[r, n] >= 0
        extent = k.carrier_half if loaded else 0.0
        radius = 0.0 if loaded else k.robot_radius
        dx = w.robot_pos[r, n, 0] - sx
        dy = w.robot_pos[r, n, 1] - sy
        _, _, depth = contact(dx, dy, extent + k.carrier_half, radius, 1.0)
        if depth > 0:
            return True
    return False


@inlined
def place_orders_run(r: int, t: int, w: World, k: Constants, x: Scratch) -> None:
    """``orders.place_orders`` for run ``r`` at the end of tick ``t``; ARRIVE rows buffered."""
    if not k.has_floor or w.ended_at[r] >= 0:
        return
    waiting = False
    for c in range(k.carriers):
        if w.arrival_time[r, c] < 0 and w.due[r, c] <= t:
            waiting = True
            break
    if not waiting:
        return
    slots = k.pickup_slots.shape[0]
    free = 0
    for s in range(slots):
        taken = False
        for c in range(k.carriers):
            if w.present[r, c] and w.carried_by[r, c] < 0 and w.slot[r, c] == s:
                taken = True
                break
        if not taken and not _robot_on(r, k.pickup_slots[s, 0], k.pickup_slots[s, 1], w, k):
            x.free_slots[r, free] = s
            free += 1
    placed = False
    for c in range(k.carriers):
        if not (w.arrival_time[r, c] < 0 and w.due[r, c] <= t):
            continue
        if free == 0:
            break
        pick = int(w.slot_pick[r, c] * free)
        s = x.free_slots[r, pick]
        for j in range(pick, free - 1):
            x.free_slots[r, j] = x.free_slots[r, j + 1]
        free -= 1
        w.carrier_pos[r, c, 0] = k.pickup_slots[s, 0]
        w.carrier_pos[r, c, 1] = k.pickup_slots[s, 1]
        w.present[r, c] = True
        w.slot[r, c] = s
        w.arrival_time[r, c] = t
        w0 = w.w0[r, c]
        if not math.isnan(w0):
            w.urgency[r, c] = min(9, math.floor(9.0 * (w0 + t) / k.horizon))
        w.urgency0[r, c] = w.urgency[r, c]
        for slot in range(k.status_delay + 1):
            w.adv_status[r, slot, c] = w.status[r, c]
            w.adv_urgency[r, slot, c] = w.urgency[r, c]
        row = x.event_count[r]
        x.event_tick[r, row] = t
        x.event_kind[r, row] = _ARRIVE
        x.event_robot[r, row] = -1
        x.event_carrier[r, row] = c
        x.event_value[r, row] = float(w.urgency[r, c])
        x.event_count[r] = row + 1
        placed = True
    if placed:
        index_obstacles(r, w, k, x)
        free_faces_run(r, w, k, x)
