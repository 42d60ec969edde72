"""Warehouse orders: sampling a run's order stream, and placing orders as they fall due.

Sampling (``sample_warehouse_scene``) uses the run's scene stream in this
order, whatever the policy:

1. ``rng.permutation(K)`` over the K pick-up slots: the first
   ``initial_orders`` are where the orders waiting at the start stand;
2. ``rng.random(C)``: each order's initial waiting time ``w0 = draw * T``
   (``T`` the urgency window in ticks);
3. ``rng.integers(D, size=C)``: each order's destination area;
4. ``rng.exponential(interval, size)``: the gaps, in ticks, between the
   orders after the initial ones; order ``k`` is due at
   ``floor(cumulative gap) + 1``;
5. ``rng.random(C)``: the number that picks each order's slot;
6. ``rng.permutation(S)`` over the S start cells (floor and drop-off cells,
   row by row): robot ``i`` starts in the ``i``-th, at the cell's centre
   plus ``(rng.random((N, 2)) - 0.5) * (cell - diameter)`` (so robots in
   neighbouring cells never overlap);
7. headings, speed factors and advertising phases as in the lab
   (``swarmtag.sim.model.scene``).

Placing (``place_orders``, the last phase of a tick): each order due by
tick ``t`` and not yet placed takes, in order number, a free pick-up slot (no
carrier standing on it that is not lifted, and no robot in the way: nobody
sets a carrier down on a robot): of the ``F`` free slots in slot
order, the one at ``floor(pick * F)``. When no slot is free the order waits,
and so do those after it. A placed order's urgency is its growing urgency at
``t`` (its waiting time started when it fell due), advertised from then on.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from swarmtag.errors import SimulationError
from swarmtag.sim.config.warehouse import Warehouse
from swarmtag.sim.model.events import EventKind, TickEvents
from swarmtag.sim.model.geometry import contact_depth
from swarmtag.sim.model.params import Params
from swarmtag.sim.model.randomness import unit_vectors
from swarmtag.sim.model.state import Scene, WorldState
from swarmtag.sim.world.motion import body_shape
from swarmtag.sim.world.predock import free_faces
from swarmtag.sim.world.urgency import growing_urgency
from swarmtag.tag import TagStatus

__all__ = ["place_orders", "sample_warehouse_scene"]


def _warehouse(params: Params) -> Warehouse:
    warehouse = params.scenario.warehouse
    assert warehouse is not None
    return warehouse


def sample_warehouse_scene(params: Params, rng: np.random.Generator) -> Scene:
    """One warehouse run's start: orders, their stream and the robots (module docs)."""
    warehouse, floor = _warehouse(params), params.floor
    assert floor is not None
    carriers, robots = params.carriers, params.robots
    slots = floor.pickup_slots
    initial = warehouse.initial_orders
    first = rng.permutation(slots.shape[0])[:initial]
    w0 = rng.random(carriers) * params.horizon
    destination = rng.integers(len(floor.destinations), size=carriers).astype(np.int64)
    gaps = rng.exponential(warehouse.order_interval / params.scenario.tick, carriers - initial)
    due = np.concatenate(
        (np.zeros(initial, dtype=np.int64), np.floor(np.cumsum(gaps)).astype(np.int64) + 1)
    )
    slot_pick = rng.random(carriers)
    if carriers > initial and due[-1] <= params.run_ticks:
        msg = (
            f"run of {params.run_ticks} ticks: the order stream outgrew the {carriers} orders "
            "allocated for it (a chance below 1e-8; use another seed)"
        )
        raise SimulationError(msg)

    cells = floor.start_cells
    chosen = cells[rng.permutation(cells.shape[0])[:robots]]
    row, col = np.divmod(chosen, floor.kind.shape[1])
    centre = np.stack(((col + 0.5) * floor.cell, (row + 0.5) * floor.cell), axis=-1)
    room = floor.cell - 2.0 * params.robot_radius
    robot_pos = centre + (rng.random((robots, 2)) - 0.5) * room
    heading = unit_vectors(rng.standard_normal((robots, 2)))
    factor = np.clip(1.0 + params.speed_variation * rng.standard_normal(robots), 0.5, 1.5)
    phase = rng.random(carriers)

    slot = np.full(carriers, -1, dtype=np.int64)
    slot[:initial] = first
    carrier_pos = np.repeat(slots[:1], carriers, axis=0)  # placeholder until placed
    carrier_pos[:initial] = slots[first]
    start = due == 0
    urgency0 = np.where(start, growing_urgency(w0, 0, params.horizon), 0).astype(np.int8)
    return Scene(
        robot_pos=robot_pos,
        carrier_pos=carrier_pos,
        urgency0=urgency0,
        order_time=due.astype(np.float64),
        w0=w0 - due,
        heading=heading,
        speed_factor=factor,
        status=np.full(carriers, TagStatus.AWAITING_PICKUP, dtype=np.int8),
        advert_phase=phase,
        due=due,
        destination=destination,
        slot=slot,
        slot_pick=slot_pick,
    )


def _robots_on(s: WorldState, params: Params, run: int) -> NDArray[np.bool_]:
    """(K,) pick-up slots on which a carrier would overlap a robot of batch row ``run``."""
    assert params.floor is not None
    slots = params.floor.pickup_slots
    extent, radius = body_shape(s.mode[run], s.target[run], params)
    offset = s.robot_pos[run][:, None, :] - slots[None, :, :]  # (N, K, 2)
    depth = contact_depth(
        offset[..., 0], offset[..., 1], (extent + params.carrier_half)[:, None], radius[:, None]
    )
    on: NDArray[np.bool_] = np.asarray((depth > 0).any(axis=0))
    return on


def place_orders(s: WorldState, params: Params, *, t: int, events: TickEvents) -> None:
    """Place the orders due by tick ``t`` on free pick-up slots, in place (module docs)."""
    if params.floor is None:
        return
    waiting = (s.arrival_time < 0) & (s.due <= t) & (s.ended_at < 0)[:, None]
    if not waiting.any():
        return
    slots = params.floor.pickup_slots
    for run in np.flatnonzero(waiting.any(axis=1)).tolist():
        standing = s.present[run] & (s.carried_by[run] < 0) & (s.slot[run] >= 0)
        taken = np.zeros(slots.shape[0], dtype=bool)
        taken[s.slot[run][standing]] = True
        taken |= _robots_on(s, params, run)
        free = np.flatnonzero(~taken)
        placed = False
        for carrier in np.flatnonzero(waiting[run]):
            if free.size == 0:
                break
            pick = int(s.slot_pick[run, carrier] * free.size)
            slot = int(free[pick])
            free = np.delete(free, pick)
            s.carrier_pos[run, carrier] = slots[slot]
            s.present[run, carrier] = True
            s.slot[run, carrier] = slot
            s.arrival_time[run, carrier] = t
            if not np.isnan(s.w0[run, carrier]):
                grown = growing_urgency(s.w0[run, carrier : carrier + 1], t, params.horizon)
                s.urgency[run, carrier] = grown[0]
            s.urgency0[run, carrier] = s.urgency[run, carrier]
            s.adv_status[run, :, carrier] = s.status[run, carrier]
            s.adv_urgency[run, :, carrier] = s.urgency[run, carrier]
            urgency = float(s.urgency[run, carrier])
            events.add_carrier(EventKind.ARRIVE, int(run), int(carrier), urgency)
            placed = True
        if placed:
            rows = slice(run, run + 1)
            obstacle = s.present[rows] & (s.carried_by[rows] < 0)
            s.free_face[rows] = free_faces(s.carrier_pos[rows], obstacle, params)
