"""What the compiled kernel is given: the world's arrays and its parameters as plain numbers.

``World`` holds the arrays of ``WorldState`` under the same names (the
kernel changes them in place; ``world_of``/``state_of`` convert without
copying), plus each run's own tick. ``Constants`` (generated,
``_constants.py``) is every kernel parameter of ``Params`` as a plain number,
then the backend's own values (``_extras.py``; the policy as a kind and a
parameter, ``policy_code``; grids; the floor's arrays). Every
array has the run axis first, so runs never share memory and a parallel
loop over runs needs no locks; the kernel's working space is ``_scratch``'s.
"""

from __future__ import annotations

from dataclasses import fields, replace
from typing import Final, NamedTuple

import numpy as np
from numpy.typing import NDArray

from swarmtag.sim.config.floor_map import PICKUP
from swarmtag.sim.fast._constants import PARAMETERS, Constants
from swarmtag.sim.fast._grid import table_bits
from swarmtag.sim.model.params import FIRST_CACHE_CAPACITY, Params
from swarmtag.sim.model.state import WorldState
from swarmtag.sim.world.broad_phase import padding

__all__ = [
    "GRID_FROM",
    "Constants",
    "World",
    "constants_of",
    "policy_code",
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
    rssi: F8
    walk_clock: I8
    seek: I8
    seek_ref: F8
    curve: F8
    look: I8
    odometry: F8
    odometry_at: F8
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
    bearing = params.bearing_factor.size > 0
    reach = params.camera_far * float(params.bearing_factor.max()) if bearing else params.camera_far
    sight = max(cell, reach)
    radio_scale = max(params.arena, params.arena_height)
    shared = {name: getattr(params, name) for name in PARAMETERS}
    return Constants(
        **shared,
        policy_kind=kind,
        policy_parameter=parameter,
        grid_cell=cell,
        robot_bits=table_bits(params.robots),
        carrier_bits=table_bits(params.carriers),
        obstacle_grid=params.carriers > GRID_FROM,
        robot_grid=params.robots > GRID_FROM,
        sight_reach=reach,
        sight_cell=sight,
        radio_grid=_radio_grid_pays(params),
        radio_cell=padding(params.radio_range, radio_scale),
        sparse_cache=params.sparse_tag_cache,
        cache_capacity=cache_capacity if params.sparse_tag_cache else 0,
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
        bearing=bearing,
        bearing_cosines=np.array(params.bearing_cos if bearing else np.zeros(2)),
        bearing_factors=np.array(params.bearing_factor if bearing else np.ones(2)),
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
