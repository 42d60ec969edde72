"""The per-tick index of a run: its obstacle carriers and the grids that find bodies near a point.

Built at the start of a tick from the state the tick starts from (the
obstacles only where they changed since: after a lift, an order, a call's
start): the obstacle list (carriers in the arena and
not carried, ascending), and for large swarms uniform grids (``_grid``) of
the obstacles and of the robots, fine ones (cells as wide as a collision's
reach) for collisions and taken faces, coarse ones (cells as wide as the
camera's range) for sightings. A query that leaves a body out leaves out
one that the exact test would reject, so the answers are the reference's.
"""

from __future__ import annotations

import math

from swarmtag.sim.fast._grid import fill
from swarmtag.sim.fast._jit import inlined
from swarmtag.sim.fast._layout import Constants, World
from swarmtag.sim.fast._scratch import Scratch

__all__ = ["copy_to_slots", "grid_robots", "index_obstacles", "index_robots"]


@inlined
def index_obstacles(r: int, w: World, k: Constants, x: Scratch) -> None:
    """List run ``r``'s obstacle carriers (ascending), box them and, where used, grid them.

    The index stays current (``Scratch.obstacles_current``) until the obstacles
    change: a tick that lifts a carrier or places an order indexes them again
    at once (``_docking.deliver_run``, ``_orders``), and a kernel call starts
    without it (``_tick.start_call``: the caller may have changed the state).
    """
    count = 0
    low_x = low_y = math.inf
    high_x = high_y = -math.inf
    for c in range(k.carriers):
        if w.present[r, c] and w.carried_by[r, c] < 0:
            cx = w.carrier_pos[r, c, 0]
            cy = w.carrier_pos[r, c, 1]
            x.obstacles[r, count] = c
            x.obstacle_x[r, count] = cx
            x.obstacle_y[r, count] = cy
            low_x = min(low_x, cx)
            high_x = max(high_x, cx)
            low_y = min(low_y, cy)
            high_y = max(high_y, cy)
            count += 1
    x.obstacle_count[r] = count
    x.obstacle_box[r, 0] = low_x
    x.obstacle_box[r, 1] = high_x
    x.obstacle_box[r, 2] = low_y
    x.obstacle_box[r, 3] = high_y
    x.obstacles_current[r] = True
    if k.obstacle_grid:
        fill(
            r,
            x.obstacle_x,
            x.obstacle_y,
            count,
            k.grid_cell,
            k.carrier_bits,
            x.obstacle_start,
            x.obstacle_items,
            x.carrier_keys,
        )
        fill(
            r,
            x.obstacle_x,
            x.obstacle_y,
            count,
            k.sight_cell,
            k.carrier_bits,
            x.sight_start,
            x.sight_items,
            x.carrier_keys,
        )


@inlined
def grid_robots(r: int, k: Constants, x: Scratch, copy: bool) -> None:
    """Sort run ``r``'s robots, at ``x.x``/``x.y``, into the fine robot grid.

    ``copy``: and copy them to their slots (``copy_to_slots``), as the
    collision passes need.
    """
    fill(
        r, x.x, x.y, k.robots, k.grid_cell, k.robot_bits, x.robot_start, x.robot_items, x.robot_keys
    )
    if copy:
        copy_to_slots(r, 0, k.robots, x)


@inlined
def copy_to_slots(r: int, lo: int, hi: int, x: Scratch) -> None:
    """Robots ``lo .. hi - 1``'s positions and bodies, copied to their slots of the robots' grid.

    The collision passes read them bucket by bucket from there
    (``robot_item_*``: ``near_within`` and the first pass), in memory order
    instead of by robot id. Each robot writes only its own slot, so ranges
    may be copied at once on several threads.
    """
    for n in range(lo, hi):
        slot = x.robot_keys[r, n]
        x.robot_item_body[r, slot, 0] = x.x[r, n]  # one cache line a robot, mostly
        x.robot_item_body[r, slot, 1] = x.y[r, n]
        x.robot_item_body[r, slot, 2] = x.extent[r, n]
        x.robot_item_body[r, slot, 3] = x.radius[r, n]
        x.robot_item_movable[r, slot] = x.movable[r, n]


@inlined
def index_robots(r: int, w: World, k: Constants, x: Scratch) -> None:
    """Grid run ``r``'s robots where they stand at the tick's start (large swarms)."""
    if not k.robot_grid:
        return
    for n in range(k.robots):
        x.x[r, n] = w.robot_pos[r, n, 0]
        x.y[r, n] = w.robot_pos[r, n, 1]
    if k.avoid_taken_faces:  # robots standing on predock points
        grid_robots(r, k, x, False)
    if k.occlusion >= 2:  # robots hiding carriers
        fill(
            r,
            x.x,
            x.y,
            k.robots,
            k.sight_cell,
            k.robot_bits,
            x.crowd_start,
            x.crowd_items,
            x.robot_keys,
        )
