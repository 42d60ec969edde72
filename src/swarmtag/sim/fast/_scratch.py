"""The compiled kernel's working space: per-run arrays reused every tick, and the event buffers.

``Scratch`` holds what a tick computes and throws away (the tick's random
numbers, the grids' tables, the collision passes' lists) and the per-run
event buffers the kernel fills (``Scratch.event_*``). Every array has the
run axis first, as in ``_layout``, so runs never share memory.
"""

from __future__ import annotations

from typing import Final, NamedTuple

import numpy as np

from swarmtag.sim.fast._grid import table_bits
from swarmtag.sim.fast._layout import B1, F8, I4, I8, S1, Constants
from swarmtag.sim.model.events import EventKind

__all__ = ["EVENT_SLOTS", "Scratch", "scratch_for"]

EVENT_SLOTS: Final = int(EventKind.DELIVER)
"""Robot event kinds (``EventKind`` 1 to ``DELIVER``); a robot has at most one of each per tick."""


class Scratch(NamedTuple):
    """Per-run working space, reused every tick, and the event buffers."""

    before_mode: S1
    before_pos: F8
    walk_gaussians: F8
    """(R, N, 2) this tick's two Gaussian numbers of each robot's walk direction (``_draws``)."""
    sidestep_gaussians: F8
    """(R, N, 2) ... and of its sidestep direction: normalised only where they are used."""
    breakdown_draw: F8
    radio_draw: F8
    noise: F8
    sight: F8
    """(R, N, C) how far each robot sees each carrier this tick (a camera fade; else (R, N, 0))."""
    seen_count: I8
    """(R, N) carriers each robot knows the position of this tick (its ``seen_*`` list)."""
    seen_list: I8
    """(R, N, C) those carriers (any order)."""
    seen_distance: F8
    """(R, N, C) the distance to each, as the policy uses it (camera noise included)."""
    blocker: I8
    """(R, N, C) the carrier that last hid each carrier from each robot (tried first), -1 none."""
    proposed: F8
    x: F8
    y: F8
    new_x: F8
    new_y: F8
    extent: F8
    radius: F8
    movable: B1
    drive_in: B1
    centred: B1
    lift: I8
    accepted: B1
    refused: B1
    raised: B1
    lower: I8
    carrier_mark: I8
    advertises: B1
    advertising: I8
    """(R, C) this tick's advertising tags that are in the arena, ``advertising_count`` of them."""
    advertising_count: I8
    advert_remainder: I8
    """(R, C) ``(t * tick_us - phase) mod advert_us`` of each tag at tick ``advert_tick``."""
    advert_tick: I8
    """(R,) the tick of ``advert_remainder``; -1: to be computed afresh (``_tick.start_call``)."""
    obstacles: I8
    """(R, C) this tick's obstacle carriers (in the arena, not carried), in index order."""
    obstacle_count: I8
    obstacles_current: B1
    """(R,) whether the obstacle index is the run's now (``_index.index_obstacles``)."""
    obstacle_x: F8
    """(R, C) the obstacles' x, in ``obstacles`` order."""
    obstacle_box: F8
    """(R, 4) the smallest and largest x, then y, of the obstacles' centres."""
    obstacle_y: F8
    obstacle_start: I4
    """(R, buckets + 1) the obstacles' grid (``_grid``): where each bucket's list starts."""
    obstacle_items: I8
    """(R, C) the obstacles' grid: positions in ``obstacles``, bucket by bucket."""
    robot_start: I4
    """(R, buckets + 1) the robots' grid: at the tick's start, then of each collision pass."""
    robot_items: I8
    """(R, N) the robots' grid: robot ids, bucket by bucket."""
    robot_item_body: F8
    """(R, N, 4) each of ``robot_items`` at the build: x, y, extent, radius (no grid: N = 0)."""
    robot_item_movable: B1
    """(R, N) ... and whether it can be pushed."""
    sight_start: I4
    """(R, buckets + 1) the obstacles' coarse grid (cells as wide as the camera's range)."""
    sight_items: I8
    """(R, C) the obstacles' coarse grid: positions in ``obstacles``, bucket by bucket."""
    crowd_start: I4
    """(R, buckets + 1) the robots' coarse grid at the tick's start (robots hide carriers)."""
    crowd_items: I8
    """(R, N) the robots' coarse grid: robot ids, bucket by bucket."""
    grid_epoch: I8
    """(R,) counts the builds of the robots' grid for the collision passes (``_motion``)."""
    moved_epoch: I8
    """(R, N) the build since which each robot moved (it is displaced while that is current)."""
    displaced: I8
    """(R, N) the robots that moved since the grid was built, ``displaced_count`` of them."""
    displaced_count: I8
    displaced_x: F8
    """(R, N) where the displaced robots are, in ``displaced`` order (the patch grid)."""
    displaced_y: F8
    patch_start: I4
    """(R, buckets + 1) the displaced robots' grid (``patch_bits``): later collision passes."""
    patch_items: I8
    patch_bits: I8
    radio_x: F8
    """(R, C) the advertising tags' x, in ``advertising`` order (radio grid)."""
    radio_y: F8
    radio_start: I4
    """(R, buckets + 1) the advertising tags' grid (cells as wide as the radio's range)."""
    radio_items: I8
    """(R, C) the advertising tags' grid: positions in ``advertising``, bucket by bucket."""
    robot_keys: I8
    """(R, N) working space of a robot grid's ``fill``."""
    carrier_keys: I8
    """(R, C) working space of an obstacle grid's ``fill``."""
    gathered: I8
    """(R, max(N, C)) bodies a grid query found, ascending (collisions)."""
    active: I8
    """(R, N) the robots a collision pass computes (after the first: those near a move)."""
    movers: I8
    """(R, N) the robots the last collision pass moved ..."""
    mover_x: F8
    """(R, N) ... and where each of them stood before it."""
    mover_y: F8
    collision_mark: I8
    """(R, N) the last ``stamp`` that put each robot on the ``active`` list."""
    stamp: I8
    """(R,) a counter for ``collision_mark``."""
    near_carriers: I8
    """(R, C) carriers a camera query found (any order)."""
    near_blockers: I8
    """(R, C) obstacles a line-of-sight query found (any order)."""
    near_robots: I8
    """(R, N) robots a query around a point or a line of sight found (any order)."""
    free_slots: I8
    """(R, K) the pick-up slots free for an order, ascending (warehouse)."""
    slot_taken: B1
    """(R, K) slots a standing carrier or a robot takes (warehouse)."""
    order_cursor: I8
    """(R,) the orders before it are placed (they are placed in order)."""

    slot_on: B1
    slot_carrier: I8
    slot_value: F8
    failure: I8
    event_count: I8
    """Rows in each run's event buffer; the buffers are the (R, capacity) ``event_*`` arrays."""
    event_tick: I8
    event_kind: S1
    event_robot: I8
    event_carrier: I8
    event_value: F8


def scratch_for(runs: int, k: Constants, capacity: int) -> Scratch:
    """Working space for ``runs`` runs of ``k``: event buffers of ``capacity`` rows, hash tables.

    The tables (``_grid``) get their full size only where a grid is used, the
    per-pair draws only where realism draws them, and the lists of carriers a
    robot knows this tick as many entries as its tag cache can hold.
    """
    robots, carriers, slots = k.robots, k.carriers, k.pickup_slots.shape[0]
    gridded = k.obstacle_grid or k.robot_grid
    robot_buckets = 4 ** table_bits(robots) + 1 if gridded else 1
    carrier_buckets = 4 ** table_bits(carriers) + 1 if gridded else 1
    n, c = (runs, robots), (runs, carriers)
    known = (runs, robots, k.cache_capacity if k.sparse_cache else carriers)
    memo = (runs, robots, 0 if k.sparse_cache else carriers)
    lost = (runs, robots, carriers if k.advertisement_loss > 0 else 0)
    noisy = (runs, robots, carriers if k.detection_noise > 0 else 0)
    fading = (runs, robots, carriers if k.camera_fade > 0 else 0)

    def floats(*shape: int) -> F8:
        return np.zeros(shape, dtype=np.float64)

    return Scratch(
        before_mode=np.zeros(n, dtype=np.int8),
        before_pos=floats(*n, 2),
        walk_gaussians=floats(*n, 2),
        sidestep_gaussians=floats(*n, 2),
        breakdown_draw=floats(*n),
        radio_draw=floats(*lost),
        noise=floats(*noisy, 2),
        sight=floats(*fading),
        seen_count=np.zeros(n, dtype=np.int64),
        seen_list=np.zeros(known, dtype=np.int64),
        seen_distance=floats(*known),
        blocker=np.full(memo, -1, dtype=np.int64),
        proposed=floats(*n, 2),
        x=floats(*n),
        y=floats(*n),
        new_x=floats(*n),
        new_y=floats(*n),
        extent=floats(*n),
        radius=floats(*n),
        movable=np.zeros(n, dtype=bool),
        drive_in=np.zeros(n, dtype=bool),
        centred=np.zeros(n, dtype=bool),
        lift=np.full(n, -1, dtype=np.int64),
        accepted=np.zeros(n, dtype=bool),
        refused=np.zeros(n, dtype=bool),
        raised=np.zeros(n, dtype=bool),
        lower=np.full(n, -1, dtype=np.int64),
        carrier_mark=np.full(c, -1, dtype=np.int64),
        advertises=np.zeros(c, dtype=bool),
        advertising=np.zeros(c, dtype=np.int64),
        advertising_count=np.zeros(runs, dtype=np.int64),
        advert_remainder=np.zeros(c, dtype=np.int64),
        advert_tick=np.full(runs, -1, dtype=np.int64),
        obstacles=np.zeros(c, dtype=np.int64),
        obstacle_count=np.zeros(runs, dtype=np.int64),
        obstacles_current=np.zeros(runs, dtype=bool),
        obstacle_x=floats(*c),
        obstacle_box=floats(runs, 4),
        obstacle_y=floats(*c),
        obstacle_start=np.zeros((runs, carrier_buckets), dtype=np.int32),
        obstacle_items=np.zeros(c, dtype=np.int64),
        robot_start=np.zeros((runs, robot_buckets), dtype=np.int32),
        robot_items=np.zeros(n, dtype=np.int64),
        robot_item_body=floats(runs, robots if k.robot_grid else 0, 4),
        robot_item_movable=np.zeros((runs, robots if k.robot_grid else 0), dtype=bool),
        sight_start=np.zeros((runs, carrier_buckets), dtype=np.int32),
        sight_items=np.zeros(c, dtype=np.int64),
        crowd_start=np.zeros((runs, robot_buckets), dtype=np.int32),
        crowd_items=np.zeros(n, dtype=np.int64),
        grid_epoch=np.zeros(runs, dtype=np.int64),
        moved_epoch=np.zeros(n, dtype=np.int64),
        displaced=np.zeros(n, dtype=np.int64),
        displaced_count=np.zeros(runs, dtype=np.int64),
        displaced_x=floats(*n),
        displaced_y=floats(*n),
        patch_start=np.zeros((runs, robot_buckets), dtype=np.int32),
        patch_items=np.zeros(n, dtype=np.int64),
        patch_bits=np.zeros(runs, dtype=np.int64),
        radio_x=floats(*c),
        radio_y=floats(*c),
        radio_start=np.zeros((runs, carrier_buckets), dtype=np.int32),
        radio_items=np.zeros(c, dtype=np.int64),
        robot_keys=np.zeros(n, dtype=np.int64),
        carrier_keys=np.zeros(c, dtype=np.int64),
        gathered=np.zeros((runs, max(robots, carriers)), dtype=np.int64),
        active=np.zeros(n, dtype=np.int64),
        movers=np.zeros(n, dtype=np.int64),
        mover_x=floats(*n),
        mover_y=floats(*n),
        collision_mark=np.full(n, -1, dtype=np.int64),
        stamp=np.zeros(runs, dtype=np.int64),
        near_carriers=np.zeros(c, dtype=np.int64),
        near_blockers=np.zeros(c, dtype=np.int64),
        near_robots=np.zeros(n, dtype=np.int64),
        free_slots=np.zeros((runs, slots), dtype=np.int64),
        slot_taken=np.zeros((runs, slots), dtype=bool),
        order_cursor=np.zeros(runs, dtype=np.int64),
        slot_on=np.zeros((*n, EVENT_SLOTS), dtype=bool),
        slot_carrier=np.zeros((*n, EVENT_SLOTS), dtype=np.int64),
        slot_value=np.zeros((*n, EVENT_SLOTS)),
        failure=np.zeros(runs, dtype=np.int64),
        event_count=np.zeros(runs, dtype=np.int64),
        event_tick=np.zeros((runs, capacity), dtype=np.int64),
        event_kind=np.zeros((runs, capacity), dtype=np.int8),
        event_robot=np.zeros((runs, capacity), dtype=np.int64),
        event_carrier=np.zeros((runs, capacity), dtype=np.int64),
        event_value=np.zeros((runs, capacity)),
    )
