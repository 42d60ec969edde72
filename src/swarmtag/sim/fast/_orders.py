"""Warehouse orders placed as they fall due, compiled: ``orders.place_orders`` for one run.

Slots are taken in ascending order and orders in order number, as in the
reference; the ARRIVE rows go straight into the run's event buffer (they
have no robot, so no robot slot).
"""

from __future__ import annotations

import math

from swarmtag.sim.fast._decide import is_loaded
from swarmtag.sim.fast._docking import free_faces_run
from swarmtag.sim.fast._floor import cell_of
from swarmtag.sim.fast._geometry import contact
from swarmtag.sim.fast._index import index_obstacles
from swarmtag.sim.fast._jit import inlined
from swarmtag.sim.fast._layout import Constants, World
from swarmtag.sim.fast._scratch import Scratch
from swarmtag.sim.model.events import EventKind

__all__ = ["place_orders_run"]

"""``EventKind.ARRIVE``."""


@inlined
def _mark_robots(r: int, w: World, k: Constants, x: Scratch) -> None:
    """Mark the slots a carrier set down on would overlap a robot (``orders._robots_on``).

    A body that overlaps a slot's square stands within a carrier's side of
    the slot, so in the slot's cell or a neighbour: each robot tests the
    slots of the 3 x 3 cells around its own.
    """
    for n in range(k.robots):
        px = w.robot_pos[r, n, 0]
        py = w.robot_pos[r, n, 1]
        loaded = is_loaded(w.mode[r, n], w.target[r, n])
        extent = k.carrier_half if loaded else 0.0
        radius = 0.0 if loaded else k.robot_radius
        row, col = cell_of(px, py, k)
        for near_row in range(max(row - 1, 0), min(row + 2, k.floor_rows)):
            for near_col in range(max(col - 1, 0), min(col + 2, k.floor_cols)):
                s = k.slot_at[near_row, near_col]
                if s < 0 or x.slot_taken[r, s]:
                    continue
                dx = px - k.pickup_slots[s, 0]
                dy = py - k.pickup_slots[s, 1]
                _, _, depth = contact(dx, dy, extent + k.carrier_half, radius, 1.0)
                if depth > 0:
                    x.slot_taken[r, s] = True


@inlined
def place_orders_run(r: int, t: int, w: World, k: Constants, x: Scratch) -> None:
    """``orders.place_orders`` for run ``r`` at the end of tick ``t``; ARRIVE rows buffered.

    Orders are placed in order number and an order waits for every earlier
    one, so the placed orders are a prefix: ``x.order_cursor`` is its end.
    """
    if not k.has_floor or w.ended_at[r] >= 0:
        return
    cursor = x.order_cursor[r]
    while cursor < k.carriers and w.arrival_time[r, cursor] >= 0:
        cursor += 1
    x.order_cursor[r] = cursor
    if cursor == k.carriers or w.due[r, cursor] > t:
        return
    slots = k.pickup_slots.shape[0]
    for s in range(slots):
        x.slot_taken[r, s] = False
    for c in range(cursor):
        if w.present[r, c] and w.carried_by[r, c] < 0 and w.slot[r, c] >= 0:
            x.slot_taken[r, w.slot[r, c]] = True
    _mark_robots(r, w, k, x)
    free = 0
    for s in range(slots):
        if not x.slot_taken[r, s]:
            x.free_slots[r, free] = s
            free += 1
    placed = False
    for c in range(cursor, k.carriers):
        if w.due[r, c] > t or free == 0:
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
        x.event_kind[r, row] = EventKind.ARRIVE
        x.event_robot[r, row] = -1
        x.event_carrier[r, row] = c
        x.event_value[r, row] = float(w.urgency[r, c])
        x.event_count[r] = row + 1
        placed = True
    if placed:
        index_obstacles(r, w, k, x)
        free_faces_run(r, w, k, x)
