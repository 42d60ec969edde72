"""Phases 3 and 4 of a tick: move, then resolve collisions (SPEC §4.2, §4.5).

Move: a walking robot drives its step along its random-walk direction; a
robot in PREDOCK drives straight at the predock point of its face, DOCK at
the carrier centre, TRANSPORT at its drop-off goal (in a warehouse, the next waypoint of
its path to the carrier's destination area) or along its sidestep,
each landing exactly on the goal when nearer than a step. Robots that
centre, lift, release or are broken stand still. Headings turn at most one
turn step per tick: a walking robot towards its walk direction, a moving
transporter towards its travel direction, and in PREDOCK towards the
carrier (the inward normal of the face); a docking robot already faces its
carrier and keeps its heading. A walking robot looking round before it
chooses (``look``) stands and turns counter-clockwise by a turn step.

Resolve (Jacobi): ``collision_iterations`` passes; each computes every
overlap from the positions at the start of the pass, then moves every robot
at once by ``(p + sum of robot pushes) + sum of carrier pushes`` (each sum
over the touching bodies in index order, starting from 0.0), then clamps it
inside the walls (x and y separately) and, in a warehouse, off the shelves
(``swarmtag.sim.world.floor``). A pair of movable robots
share a push half and half; a robot that stands still is not moved and the
other takes the whole push; carriers (present, not carried) are fixed
obstacles, except the one a robot is under (docking or driving out). A
loaded robot's body is its carrier's square. Pushing out along the contact
normal keeps the tangential part of the move: robots slide along what they
touch.

The pairs that touch are found with dense all-pairs arrays in small swarms
and with uniform grids in large ones (``swarmtag.sim.world.broad_phase``); both
give the same pairs in the same order, so the same sums.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from swarmtag.sim.config.floor_map import FloorMap
from swarmtag.sim.model.geometry import (
    FACE_NORMALS,
    Float,
    contact_depth,
    contact_xy,
    length,
    step_towards,
    turn_towards,
)
from swarmtag.sim.model.indexing import STILL_MODES, at_robots, in_modes, is_loaded
from swarmtag.sim.model.params import Params
from swarmtag.sim.model.state import Int, Mode, WorldState
from swarmtag.sim.world.broad_phase import Grid, build_grid, grid_pays, near_points, sorted_pairs
from swarmtag.sim.world.floor import cells_of, keep_off_shelves, transport_waypoints

__all__ = ["body_shape", "move", "resolve"]


def body_shape(
    mode: NDArray[np.int8], target: NDArray[np.int64], params: Params
) -> tuple[Float, Float]:
    """Each robot's rounded-box extent and radius: a disc, or its carrier's square when loaded."""
    loaded = is_loaded(mode, target)
    extent: Float = np.where(loaded, params.carrier_half, 0.0).astype(np.float64)
    radius: Float = np.where(loaded, 0.0, params.robot_radius).astype(np.float64)
    return extent, radius


def move(s: WorldState, params: Params) -> Float:
    """Proposed positions (R, N, 2) before collisions.

    Turns headings and counts down sidesteps in place.
    """
    mode, pos, speed = s.mode, s.robot_pos, s.speed
    walking = mode == int(Mode.WALK)
    approaching = mode == int(Mode.PREDOCK)
    carrying = mode == int(Mode.TRANSPORT)
    if params.floor is not None and carrying.any():
        destination = at_robots(s.destination, s.target)
        waypoint = transport_waypoints(pos, destination, params.floor)
        np.copyto(s.goal, waypoint, where=carrying[..., None])
    centre = at_robots(s.carrier_pos, s.target)
    normal = FACE_NORMALS[np.maximum(s.face, 0)]
    predock = centre + normal * params.predock_offset
    goal = np.where(
        approaching[..., None],
        predock,
        np.where((mode == int(Mode.DOCK))[..., None], centre, s.goal),
    )
    driving = in_modes(mode, (Mode.PREDOCK, Mode.DOCK, Mode.TRANSPORT))
    sidestepping = carrying & (s.sidestep > 0)
    towards = step_towards(pos, goal, speed)
    walked = pos + s.walk * speed[..., None]
    walk_facing = s.walk
    if params.look_ticks > 0:  # looking round: stand and turn counter-clockwise
        looking = (walking & (s.look >= 0))[..., None]
        walked = np.where(looking, pos, walked)
        left = np.stack((-s.heading[..., 1], s.heading[..., 0]), axis=-1)
        walk_facing = np.where(looking, left, s.walk)
    sidestep = pos + s.sidestep_dir * speed[..., None]
    proposed = np.where(
        walking[..., None],
        walked,
        np.where(sidestepping[..., None], sidestep, np.where(driving[..., None], towards, pos)),
    )
    s.sidestep[sidestepping] -= 1

    travel = proposed - pos
    distance = length(travel)
    safe = np.where(distance > 0, distance, 1.0)
    direction = travel / safe[..., None]
    facing = np.where(
        approaching[..., None],
        -normal,
        np.where(walking[..., None], walk_facing, direction),
    )
    turning = approaching | walking | (carrying & (distance > 0))
    if turning.any():
        turned = turn_towards(s.heading, facing, params.turn_cos, params.turn_sin)
        np.copyto(s.heading, turned, where=turning[..., None])
    return proposed


@dataclass(frozen=True, eq=False)
class _Bodies:
    """What one tick's collision passes need, computed once per tick.

    Pairs come from dense (R, N, N) and (R, N, C) arrays for small swarms
    (``reach`` and ``allowed``, ``blocks``) or from uniform grids
    (``swarmtag.sim.world.broad_phase``: robots binned every pass, obstacle
    carriers once per tick in ``blocks``); both give the same pairs.
    """

    extent: Float
    radius: Float
    movable: NDArray[np.bool_]
    """(R, N) robots that can be pushed (not standing still)."""
    ghost: Int
    carrier_x: Float
    carrier_y: Float
    carrier_half: float
    carrier_reach: Float
    """(R, N, 1) ``(extent + carrier_half) + radius``: how near a carrier's centre touches."""
    margin: Float
    arena: float
    arena_height: float
    floor: FloorMap | None
    """The warehouse floor whose shelves keep robots out (None: the lab arena)."""
    start_row: Int
    start_col: Int
    """(R, N) the cell each robot started the tick in (warehouse only; else empty)."""
    reach_bound: float
    """No robot pair's reach ``(extent_i + extent_j) + (radius_i + radius_j)`` exceeds it."""
    reach: Float | None
    """(R, N, N) each robot pair's reach (dense path), else None."""
    allowed: NDArray[np.bool_] | None
    """(R, N, N) pairs that can push robot i: i movable, j another robot (dense path)."""
    blocks: NDArray[np.bool_] | Grid
    """(R, N, C) carriers that block each robot (dense path), or the obstacle carriers
    (present, not carried) binned (grid path)."""
    carrier_bound: float
    """No robot's reach against a carrier exceeds it."""


def _bodies(s: WorldState, params: Params) -> _Bodies:
    runs, robots = s.mode.shape
    carriers = s.carrier_pos.shape[1]
    extent, radius = body_shape(s.mode, s.target, params)
    movable = ~in_modes(s.mode, STILL_MODES)
    obstacle = s.present & (s.carried_by < 0)
    carrier_reach = (extent + params.carrier_half)[..., None] + radius[..., None]
    reach_bound = 2.0 * float(np.max(extent + radius))
    carrier_bound = float(np.max(carrier_reach))
    reach = allowed = None
    blocks: NDArray[np.bool_] | Grid
    if not grid_pays("robots", runs * robots, robots):
        index = np.arange(robots)
        reach = (extent[:, :, None] + extent[:, None, :]) + (
            radius[:, :, None] + radius[:, None, :]
        )
        allowed = movable[:, :, None] & (index[:, None] != index[None, :])
    if grid_pays("obstacles", runs * robots, carriers):
        blocks = build_grid(s.carrier_pos[..., 0], s.carrier_pos[..., 1], obstacle, carrier_bound)
    else:
        others = np.arange(carriers) != s.ghost[..., None]
        blocks = obstacle[:, None, :] & others & movable[..., None]
    empty = np.zeros((0,), dtype=np.int64)
    start = (empty, empty) if params.floor is None else cells_of(params.floor, s.robot_pos)
    return _Bodies(
        extent=extent,
        radius=radius,
        movable=movable,
        ghost=s.ghost,
        carrier_x=s.carrier_pos[..., 0],
        carrier_y=s.carrier_pos[..., 1],
        carrier_half=params.carrier_half,
        carrier_reach=carrier_reach,
        margin=extent + radius,
        arena=params.arena,
        arena_height=params.arena_height,
        floor=params.floor,
        start_row=start[0],
        start_col=start[1],
        reach_bound=reach_bound,
        reach=reach,
        allowed=allowed,
        blocks=blocks,
        carrier_bound=carrier_bound,
    )


def _summed(
    rows: Int, robots: Int, shape: tuple[int, int], push_x: Float, push_y: Float
) -> tuple[Float, Float]:
    """Per-robot sums of pushes, in the order given (index order: ``np.nonzero``'s)."""
    flat = rows * shape[1] + robots
    size = shape[0] * shape[1]
    sum_x: Float = np.bincount(flat, weights=push_x, minlength=size).astype(np.float64)
    sum_y: Float = np.bincount(flat, weights=push_y, minlength=size).astype(np.float64)
    return sum_x.reshape(shape), sum_y.reshape(shape)


def _robot_pairs(x: Float, y: Float, b: _Bodies) -> tuple[Int, Int, Int]:
    """(run, i, j), in ``np.nonzero`` order: robot pairs close enough to touch that push i.

    Close enough: ``|x_i - x_j|`` and ``|y_i - y_j|`` both under the pair's
    reach; i movable, j another robot.
    """
    if b.reach is not None and b.allowed is not None:
        dx = x[:, :, None] - x[:, None, :]
        dy = y[:, :, None] - y[:, None, :]
        near = (np.abs(dx) < b.reach) & (np.abs(dy) < b.reach) & b.allowed
        runs, robots, others = np.nonzero(near)
        return runs, robots, others
    grid = build_grid(x, y, np.ones(x.shape, dtype=bool), b.reach_bound)
    runs, robots, others = near_points(grid, x, y, b.movable, b.reach_bound)
    reach = (b.extent[runs, robots] + b.extent[runs, others]) + (
        b.radius[runs, robots] + b.radius[runs, others]
    )
    dx = x[runs, robots] - x[runs, others]
    dy = y[runs, robots] - y[runs, others]
    near = (np.abs(dx) < reach) & (np.abs(dy) < reach) & (robots != others)
    shape = (*x.shape, x.shape[1])
    return sorted_pairs(runs[near], robots[near], others[near], shape)


def _carrier_pairs(x: Float, y: Float, b: _Bodies) -> tuple[Int, Int, Int]:
    """(run, i, c), in ``np.nonzero`` order: robots close enough to touch a blocking carrier.

    Blocks: present, not carried, not the carrier the robot is under, and
    the robot movable.
    """
    if not isinstance(b.blocks, Grid):
        cx = x[:, :, None] - b.carrier_x[:, None, :]
        cy = y[:, :, None] - b.carrier_y[:, None, :]
        close = (np.abs(cx) < b.carrier_reach) & (np.abs(cy) < b.carrier_reach) & b.blocks
        runs, robots, carriers = np.nonzero(close)
        return runs, robots, carriers
    runs, robots, carriers = near_points(b.blocks, x, y, b.movable, b.carrier_bound)
    reach = b.carrier_reach[runs, robots, 0]
    cx = x[runs, robots] - b.carrier_x[runs, carriers]
    cy = y[runs, robots] - b.carrier_y[runs, carriers]
    close = (np.abs(cx) < reach) & (np.abs(cy) < reach) & (carriers != b.ghost[runs, robots])
    shape = (*x.shape, b.carrier_x.shape[1])
    return sorted_pairs(runs[close], robots[close], carriers[close], shape)


def _collision_pass(x: Float, y: Float, b: _Bodies) -> tuple[Float, Float]:
    """One Jacobi pass: the positions after it.

    Where no pair is that close (most passes of small swarms), the pushes are
    zeros without the contact arithmetic: the same sums, a fraction of the calls.
    """
    shape = x.shape
    runs, robots, others = _robot_pairs(x, y, b)
    robot_x = robot_y = np.zeros(shape)
    if runs.size:
        push_x, push_y, _ = contact_xy(
            x[runs, robots] - x[runs, others],
            y[runs, robots] - y[runs, others],
            b.extent[runs, robots] + b.extent[runs, others],
            b.radius[runs, robots] + b.radius[runs, others],
            np.where(robots < others, -1.0, 1.0),
        )
        weight = np.where(b.movable[runs, others], 0.5, 1.0)  # shared, or all of it
        robot_x, robot_y = _summed(runs, robots, shape, push_x * weight, push_y * weight)

    runs_c, robots_c, carriers = _carrier_pairs(x, y, b)
    carrier_x = carrier_y = np.zeros(shape)
    if runs_c.size:
        push_x, push_y, _ = contact_xy(
            x[runs_c, robots_c] - b.carrier_x[runs_c, carriers],
            y[runs_c, robots_c] - b.carrier_y[runs_c, carriers],
            b.extent[runs_c, robots_c] + b.carrier_half,
            b.radius[runs_c, robots_c],
            1.0,
        )
        carrier_x, carrier_y = _summed(runs_c, robots_c, shape, push_x, push_y)
    new_x = (x + robot_x) + carrier_x
    new_y = (y + robot_y) + carrier_y
    new_x = np.minimum(np.maximum(new_x, b.margin), b.arena - b.margin)
    new_y = np.minimum(np.maximum(new_y, b.margin), b.arena_height - b.margin)
    if b.floor is not None:
        new_x, new_y = keep_off_shelves(
            new_x,
            new_y,
            extent=b.extent,
            radius=b.radius,
            row=b.start_row,
            col=b.start_col,
            floor=b.floor,
        )
    return new_x, new_y


def resolve(s: WorldState, proposed: Float, params: Params) -> None:
    """Resolve collisions of the ``proposed`` positions and write the outcome into ``s``.

    Sets positions, the contact push, the positions of carried carriers, and
    forgets the carrier a robot was under once it is clear of it.
    A pass is a function of the positions alone: one that moves nobody is a
    fixed point, so the remaining passes (which would change nothing) are skipped.
    """
    bodies = _bodies(s, params)
    x, y = proposed[..., 0], proposed[..., 1]
    for _ in range(params.collision_iterations):
        new_x, new_y = _collision_pass(x, y, bodies)
        settled = np.array_equal(new_x, x) and np.array_equal(new_y, y)
        x, y = new_x, new_y
        if settled:
            break
    position = np.stack((x, y), axis=-1)

    np.copyto(s.contact, position - proposed)
    np.copyto(s.robot_pos, position)
    loaded = is_loaded(s.mode, s.target)
    rows, holders = np.nonzero(loaded)
    s.carrier_pos[rows, s.target[rows, holders]] = position[rows, holders]

    under = s.ghost >= 0
    if under.any():
        offset = position - at_robots(s.carrier_pos, s.ghost)
        depth = contact_depth(
            offset[..., 0], offset[..., 1], bodies.extent + params.carrier_half, bodies.radius
        )
        clear = under & (depth <= 0) & ~in_modes(s.mode, (Mode.DOCK, Mode.CENTRE))
        s.ghost[clear] = -1
