"""Checking mode: world-state invariants verified after every tick (tests, debugging).

Rules (each failure is an ``InvariantError`` naming the run, tick and rule):

- every robot body (disc, or square when loaded) lies inside the arena;
- no two robots, and no robot and obstacle carrier, overlap by more than
  ``OVERLAP_TOLERANCE`` (a robot may overlap the carrier it is under, also
  when another robot has just lifted that carrier);
- a carrier is delivered at most once and leaves the arena exactly then;
- tag statuses change only along the robots' two lifecycle transitions;
- a carried carrier sits exactly at its robot's position;
- event times are the current tick, and ticks only increase.
"""

from __future__ import annotations

from typing import Final

import numpy as np
from numpy.typing import NDArray

from swarmtag.errors import InvariantError
from swarmtag.sim.model.events import TickEvents
from swarmtag.sim.model.geometry import contact_depth
from swarmtag.sim.model.indexing import is_loaded
from swarmtag.sim.model.params import Params
from swarmtag.sim.model.state import WorldState
from swarmtag.sim.world.floor import keep_off_shelves
from swarmtag.sim.world.handling import ROBOT_WRITE_ALLOWED
from swarmtag.sim.world.motion import body_shape

__all__ = ["OVERLAP_TOLERANCE", "check_tick"]

OVERLAP_TOLERANCE: Final = 0.02
"""Metres two bodies may overlap after collision resolution (a few passes leave a residue)."""
_WALL_TOLERANCE: Final = 1e-9


def _fail(state: WorldState, mask: NDArray[np.bool_], rule: str) -> None:
    rows = np.argwhere(mask)
    first = rows[0]
    run = int(state.run_ids[first[0]])
    msg = f"run {run}, tick {state.tick}: {rule} (at index {tuple(int(i) for i in first[1:])})"
    raise InvariantError(msg)


def _bodies(state: WorldState, params: Params) -> None:
    extent, radius = body_shape(state.mode, state.target, params)
    margin = (extent + radius)[..., None]
    size = np.array([params.arena, params.arena_height])
    outside = (state.robot_pos < margin - _WALL_TOLERANCE) | (
        state.robot_pos > size - margin + _WALL_TOLERANCE
    )
    if outside.any():
        _fail(
            state, np.logical_or(outside[..., 0], outside[..., 1]), "a robot is outside the arena"
        )
    if params.floor is not None:
        x, y = state.robot_pos[..., 0], state.robot_pos[..., 1]
        row, col = params.floor.cell_of(x, y)
        kept_x, kept_y = keep_off_shelves(
            x, y, extent=extent, radius=radius, row=row, col=col, floor=params.floor
        )
        into = np.maximum(np.abs(kept_x - x), np.abs(kept_y - y))
        on_shelf = params.floor.blocked[row + 1, col + 1] | (into > OVERLAP_TOLERANCE)
        if on_shelf.any():
            _fail(state, on_shelf, f"a robot overlaps a shelf by {into.max():.4f} m")
    robots = state.mode.shape[1]
    between = state.robot_pos[:, :, None, :] - state.robot_pos[:, None, :, :]
    depth = contact_depth(
        between[..., 0],
        between[..., 1],
        extent[:, :, None] + extent[:, None, :],
        radius[:, :, None] + radius[:, None, :],
    )
    depth[:, np.arange(robots), np.arange(robots)] = 0.0
    # A robot under a carrier that another robot has just lifted overlaps that robot's footprint.
    loaded = is_loaded(state.mode, state.target)
    under = (state.ghost[:, :, None] >= 0) & (
        state.ghost[:, :, None] == np.where(loaded, state.target, -2)[:, None, :]
    )
    depth = np.where(under | under.transpose(0, 2, 1), 0.0, depth)
    deep: NDArray[np.bool_] = depth > OVERLAP_TOLERANCE
    if deep.any():
        _fail(state, deep, f"two robots overlap by {depth.max():.4f} m")
    against = state.robot_pos[:, :, None, :] - state.carrier_pos[:, None, :, :]
    depth = contact_depth(
        against[..., 0],
        against[..., 1],
        extent[..., None] + params.carrier_half,
        np.broadcast_to(radius[..., None], against.shape[:-1]),
    )
    carriers = np.arange(state.carrier_pos.shape[1])
    obstacle = (state.present & (state.carried_by < 0))[:, None, :] & (
        carriers != state.ghost[..., None]
    )
    deep = obstacle & (depth > OVERLAP_TOLERANCE)
    if deep.any():
        worst = float(np.where(obstacle, depth, 0.0).max())
        _fail(state, deep, f"a robot overlaps a carrier by {worst:.4f} m")


def _carriers(before: WorldState, after: WorldState) -> None:
    redelivered = (before.delivery_time >= 0) & (after.delivery_time != before.delivery_time)
    if redelivered.any():
        _fail(after, redelivered, "a carrier was delivered twice")
    left = before.present & ~after.present
    if (left != ((before.delivery_time < 0) & (after.delivery_time >= 0))).any():
        _fail(after, left, "a carrier left the arena other than by delivery")
    back = ~before.present & after.present & (before.delivery_time >= 0)
    if back.any():
        _fail(after, back, "a delivered carrier came back")
    placed = ~before.present & after.present
    if (placed & (after.arrival_time != after.tick)).any():
        _fail(after, placed & (after.arrival_time != after.tick), "a carrier appeared unplaced")
    changed = before.status != after.status
    allowed = ROBOT_WRITE_ALLOWED[before.status.astype(np.int64), after.status.astype(np.int64)]
    if (changed & ~allowed).any():
        _fail(after, changed & ~allowed, "a tag status changed along no lifecycle transition")
    loaded = is_loaded(after.mode, after.target)
    runs, robots = np.nonzero(loaded)
    carriers = after.target[runs, robots]
    misplaced = (after.carrier_pos[runs, carriers] != after.robot_pos[runs, robots]).any(axis=-1)
    held = after.carried_by[runs, carriers] == robots
    if misplaced.any() or not held.all():
        mask = np.zeros(loaded.shape, dtype=bool)
        mask[runs[misplaced | ~held], robots[misplaced | ~held]] = True
        _fail(after, mask, "a carried carrier is not with its robot")


def check_tick(before: WorldState, after: WorldState, events: TickEvents, params: Params) -> None:
    """Raise ``InvariantError`` if the tick from ``before`` to ``after`` broke a rule."""
    if after.tick != before.tick + 1:
        msg = f"tick went from {before.tick} to {after.tick}"
        raise InvariantError(msg)
    for entry in events.entries:
        if entry.mask.shape != after.mode.shape:
            msg = f"tick {after.tick}: {entry.kind.label} events have shape {entry.mask.shape}"
            raise InvariantError(msg)
    _bodies(after, params)
    _carriers(before, after)
