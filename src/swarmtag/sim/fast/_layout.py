"""What the compiled kernel is given: the world's arrays, its parameters, its scratch space.

``World`` holds the arrays of ``WorldState`` under the same names (the
kernel changes them in place; ``world_of``/``state_of`` convert without
copying), plus each run's own tick. ``Constants`` is ``Params`` as plain
numbers (the policy as a kind and a parameter, ``policy_code``). ``Scratch``
is per-run working space the kernel reuses every tick, and the per-run event
buffers it fills (``Scratch.event_*``): every array has the run axis first, so
runs never share memory and a parallel loop over runs needs no locks.
"""

from __future__ import annotations

from dataclasses import fields, replace
from typing import Final, NamedTuple

import numpy as np
from numpy.typing import NDArray

from swarmtag.sim.broad_phase import padding
from swarmtag.sim.fast._grid import table_bits
from swarmtag.sim.floor_map import PICKUP
from swarmtag.sim.params import FIRST_CACHE_CAPACITY, Params
from swarmtag.sim.state import WorldState

__all__ = [
    "EVENT_SLOTS",
    "GRID_FROM",
    "Constants",
    "Scratch",
    "World",
    "constants_of",
    "policy_code",
    "scratch_for",
    "state_of",
    "world_of",
]

F8 = NDArray[np.float64]
I8 = NDArray[np.int64]
I4 = NDArray[np.int32]
B1 = NDArray[np.bool_]
S1 = NDArray[np.int8]

GRID_FROM: Final = 96
"""Bodies of a kind beyond which the kernel finds neighbours with a grid instead of a scan."""
EVENT_SLOTS: Final = 8
"""Robot event kinds (``EventKind`` 1-8); a robot has at most one of each per tick."""


class World(NamedTuple):
    """The arrays of ``WorldState`` (same names, same shapes) and each run's tick."""

    run_tick: I8
    run_ids: I8
    robot_pos: F8
    heading: F8
    walk: F8
    speed: F8
    mode: S1
    target: I8
    face: I8
    pursuit_start: I8
    timer: I8
    ghost: I8
    redirect: B1
    contact: F8
    stuck: I8
    sidestep: I8
    sidestep_dir: F8
    goal: F8
    blocked_until: I8
    known_status: S1
    known_urgency: S1
    heard_tick: I8
    seen_tick: I8
    seen_pos: F8
    walk_clock: I8
    carrier_pos: F8
    status: S1
    urgency: S1
    present: B1
    carried_by: I8
    w0: F8
    urgency0: S1
    order_time: F8
    free_face: B1
    advert_phase: I8
    adv_status: S1
    adv_urgency: S1
    pickup_time: I8
    delivery_time: I8
    deliverer: I8
    delivery_urgency: S1
    ended_at: I8
    operator_counter: I8
    due: I8
    arrival_time: I8
    destination: I8
    slot: I8
    slot_pick: F8
    cache_count: I8
    """(R, N) entries in each robot's sparse tag cache (``_tag_cache``; the kernel's own)."""
    cache_carrier: I8
    """(R, N, K) the carrier of each entry (in no order); K is 0 with dense caches."""
    cache_status: S1
    cache_urgency: S1
    cache_blocked: I8
    """(R, N, K) the first tick at which the robot may select the entry's carrier again."""


_KERNEL_ONLY: Final = (
    "run_tick",
    "cache_count",
    "cache_carrier",
    "cache_status",
    "cache_urgency",
    "cache_blocked",
)
"""``World`` fields that are not ``WorldState``'s."""


class Constants(NamedTuple):
    """``Params`` as the numbers the kernel reads (lengths in metres, times in ticks)."""

    robots: int
    carriers: int
    arena: float
    dropoff_left: float
    robot_radius: float
    carrier_half: float
    turn_cos: float
    turn_sin: float
    detection_radius: float
    split: bool
    radio_range: float
    camera_range: float
    occlusion: int
    memory_ticks: int
    tick_us: int
    advert_us: int
    walk_turn_ticks: int
    avoid_taken_faces: bool
    predock_offset: float
    arrival_tolerance: float
    transport_x: float
    dock_ticks: int
    lift_ticks: int
    release_ticks: int
    timeout_ticks: int
    cooldown_ticks: int
    stuck_ticks: int
    sidestep_ticks: int
    collision_iterations: int
    run_ticks: int
    growing: bool
    horizon: float
    advertisement_loss: float
    status_delay: int
    detection_noise: float
    breakdown: float
    policy_kind: int
    policy_parameter: float
    grid_cell: float
    """Side of a grid cell: the longest reach of a collision (two loaded robots, ...)."""
    robot_bits: int
    """The robots' grid tables have ``2**bits`` by ``2**bits`` buckets (``_grid.table_bits``)."""
    carrier_bits: int
    """The same for the carriers' grid tables."""
    obstacle_grid: bool
    """Find each robot's obstacle carriers with the grid (many carriers) rather than a scan."""
    robot_grid: bool
    """Find each robot's neighbours with the grid (many robots) rather than a scan."""
    sight_cell: float
    """Side of a coarse grid cell: the camera's range (at least ``grid_cell``)."""
    radio_grid: bool
    """Find the advertising tags each robot may hear with a grid (many carriers, split)."""
    radio_cell: float
    """Side of a radio grid cell: the radio's range, padded against rounding."""
    sparse_cache: bool
    """Robots keep their tag caches as short lists (``Params.sparse_tag_cache``)."""
    cache_capacity: int
    """Entries of a sparse tag cache (``World.cache_*``); 0 with dense caches."""
    arena_height: float
    has_floor: bool
    """A warehouse floor (the ``floor_*`` arrays and ``pickup_slots``); else the lab arena."""
    floor_cell: float
    floor_rows: int
    floor_cols: int
    floor_blocked: B1
    """(rows + 2, cols + 2) shelves and the wall around (``FloorMap.blocked``)."""
    floor_area: I8
    """(rows, cols) drop-off area id of each cell, -1 none."""
    floor_waypoint: F8
    """(D, rows, cols, 2) the next waypoint towards each destination."""
    floor_destinations: I8
    """(D,) the destination (area) ids."""
    pickup_slots: F8
    """(K, 2) the pick-up slots' centres (one dummy slot in the lab arena)."""
    slot_at: I8
    """(rows, cols) the pick-up slot of each cell, -1 none."""


class Scratch(NamedTuple):
    """Per-run working space, reused every tick, and the event buffers."""

    before_mode: S1
    before_pos: F8
    walk_in: F8
    sidestep_in: F8
    breakdown_draw: F8
    radio_draw: F8
    noise: F8
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
    obstacles: I8
    """(R, C) this tick's obstacle carriers (in the arena, not carried), in index order."""
    obstacle_count: I8
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
    """(R, N) the robots a collision pass computes (large swarms: those near a move)."""
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


def policy_code(params: Params) -> tuple[int, float]:
    """The policy as the kernel's ``(kind, parameter)``: see ``swarmtag.policy.kernel_form``."""
    kind, parameter = params.policy.kernel_form
    return kind, parameter


def _radio_grid_pays(params: Params) -> bool:
    """Whether hearing looks up tags in a grid: many carriers, a radio short for the floor.

    The cells around a robot cover ``(4 * range)**2``; where that is not well
    under the floor, scanning this tick's advertising tags is cheaper than
    binning them (the warehouse hall, 36 m x 24 m with a 10 m radio, ran 1.3x
    slower with the grid).
    """
    reach = 4.0 * params.radio_range
    floor = params.arena * params.arena_height
    return (
        params.split
        and params.memory_ticks == 0
        and params.carriers > GRID_FROM
        and reach * reach <= floor
    )


def cache_capacity_for(params: Params) -> int:
    """The first capacity of ``params``' sparse tag caches; 0 where they are dense.

    At most the places a carrier can stand on the floor (the pick-up slots
    of a warehouse, every carrier in the lab) + 2, which never overflows
    (``_tag_cache``).
    """
    if not params.sparse_tag_cache:
        return 0
    return min(FIRST_CACHE_CAPACITY, cache_bound(params))


def cache_bound(params: Params) -> int:
    """Entries a sparse tag cache never needs more of (``_tag_cache``)."""
    places = params.carriers if params.floor is None else len(params.floor.pickup_slots)
    return places + 2


def constants_of(params: Params, cache_capacity: int = 0) -> Constants:
    """The kernel's constants for ``params`` (writable copies of the floor's arrays).

    The lab arena gets one-cell dummies of the same types, so both compile to one kernel.
    ``cache_capacity``: entries of each robot's sparse tag cache (``Params.sparse_tag_cache``).
    """
    kind, parameter = policy_code(params)
    floor = params.floor
    if floor is None:
        blocked = np.zeros((3, 3), dtype=bool)
        area = np.full((1, 1), -1, dtype=np.int64)
        waypoint = np.zeros((1, 1, 1, 2))
        destinations = np.zeros(1, dtype=np.int64)
        slots = np.zeros((1, 2))
        slot_at = np.full((1, 1), -1, dtype=np.int64)
        floor_cell, rows, cols = 1.0, 1, 1
    else:
        blocked = np.array(floor.blocked, dtype=bool)
        area = np.array(floor.area, dtype=np.int64)
        waypoint = np.array(floor.waypoint, dtype=np.float64)
        destinations = np.array(floor.destinations, dtype=np.int64)
        slots = np.array(floor.pickup_slots, dtype=np.float64)
        slot_at = np.full(floor.kind.shape, -1, dtype=np.int64)
        slot_at[floor.kind == PICKUP] = np.arange(slots.shape[0])  # row by row, as the slots
        floor_cell, rows, cols = floor.cell, floor.rows, floor.cols
    half, radius = params.carrier_half, params.robot_radius
    cell = max(2 * half, half + radius, 2 * radius)
    sight = max(cell, params.camera_range)
    radio_scale = max(params.arena, params.arena_height)
    return Constants(
        robots=params.robots,
        carriers=params.carriers,
        arena=params.arena,
        dropoff_left=params.dropoff_left,
        robot_radius=params.robot_radius,
        carrier_half=params.carrier_half,
        turn_cos=params.turn_cos,
        turn_sin=params.turn_sin,
        detection_radius=params.detection_radius,
        split=params.split,
        radio_range=params.radio_range,
        camera_range=params.camera_range,
        occlusion=params.occlusion,
        memory_ticks=params.memory_ticks,
        tick_us=params.tick_us,
        advert_us=params.advert_us,
        walk_turn_ticks=params.walk_turn_ticks,
        avoid_taken_faces=params.avoid_taken_faces,
        predock_offset=params.predock_offset,
        arrival_tolerance=params.arrival_tolerance,
        transport_x=params.transport_x,
        dock_ticks=params.dock_ticks,
        lift_ticks=params.lift_ticks,
        release_ticks=params.release_ticks,
        timeout_ticks=params.timeout_ticks,
        cooldown_ticks=params.cooldown_ticks,
        stuck_ticks=params.stuck_ticks,
        sidestep_ticks=params.sidestep_ticks,
        collision_iterations=params.collision_iterations,
        run_ticks=params.run_ticks,
        growing=params.growing,
        horizon=params.horizon,
        advertisement_loss=params.advertisement_loss,
        status_delay=params.status_delay,
        detection_noise=params.detection_noise,
        breakdown=params.breakdown,
        policy_kind=kind,
        policy_parameter=parameter,
        grid_cell=cell,
        robot_bits=table_bits(params.robots),
        carrier_bits=table_bits(params.carriers),
        obstacle_grid=params.carriers > GRID_FROM,
        robot_grid=params.robots > GRID_FROM,
        sight_cell=sight,
        radio_grid=_radio_grid_pays(params),
        radio_cell=padding(params.radio_range, radio_scale),
        sparse_cache=params.sparse_tag_cache,
        cache_capacity=cache_capacity if params.sparse_tag_cache else 0,
        arena_height=params.arena_height,
        has_floor=floor is not None,
        floor_cell=floor_cell,
        floor_rows=rows,
        floor_cols=cols,
        floor_blocked=blocked,
        floor_area=area,
        floor_waypoint=waypoint,
        floor_destinations=destinations,
        pickup_slots=slots,
        slot_at=slot_at,
    )


def world_of(state: WorldState, *, copy: bool = True, cache_capacity: int = 0) -> World:
    """The kernel's view of ``state`` (a copy unless ``copy`` is false): every run at its tick.

    Each robot's sparse tag cache starts empty with room for ``cache_capacity`` entries.
    """
    source = state.copy() if copy else state
    arrays = {
        f.name: getattr(source, f.name) for f in fields(WorldState) if f.name in World._fields
    }
    entries = (state.runs, state.robot_pos.shape[1], cache_capacity)
    return World(
        run_tick=np.full(state.runs, state.tick, dtype=np.int64),
        cache_count=np.zeros(entries[:2], dtype=np.int64),
        cache_carrier=np.full(entries, -1, dtype=np.int64),
        cache_status=np.zeros(entries, dtype=np.int8),
        cache_urgency=np.zeros(entries, dtype=np.int8),
        cache_blocked=np.zeros(entries, dtype=np.int64),
        **arrays,
    )


def state_of(world: World, template: WorldState) -> WorldState:
    """``world``'s arrays as a ``WorldState`` (no copy) at the latest tick any run reached."""
    arrays = {name: getattr(world, name) for name in World._fields if name not in _KERNEL_ONLY}
    tick = int(world.run_tick.max()) if world.run_tick.size else template.tick
    return replace(template, tick=tick, **arrays)


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

    def floats(*shape: int) -> F8:
        return np.zeros(shape, dtype=np.float64)

    return Scratch(
        before_mode=np.zeros(n, dtype=np.int8),
        before_pos=floats(*n, 2),
        walk_in=floats(*n, 2),
        sidestep_in=floats(*n, 2),
        breakdown_draw=floats(*n),
        radio_draw=floats(*lost),
        noise=floats(*noisy, 2),
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
        obstacles=np.zeros(c, dtype=np.int64),
        obstacle_count=np.zeros(runs, dtype=np.int64),
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
