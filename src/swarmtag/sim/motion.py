"""Phases 3 and 4 of a tick: move, then resolve collisions (SPEC §4.2, §4.5).

Move: a walking robot drives its step along its random-walk direction; a
robot in PREDOCK drives straight at the predock point of its face, DOCK at
the carrier centre, TRANSPORT at its drop-off goal (or along its sidestep),
each landing exactly on the goal when nearer than a step. Robots that
centre, lift, release or are broken stand still. Headings turn at most one
turn step per tick: a walking robot towards its walk direction, a moving
transporter towards its travel direction, and in PREDOCK towards the
carrier (the inward normal of the face); a docking robot already faces its
carrier and keeps its heading.

Resolve (Jacobi): ``collision_iterations`` passes; each computes every
overlap from the positions at the start of the pass, then moves every robot
at once by ``(p + sum of robot pushes) + sum of carrier pushes`` (each sum
over the touching bodies in index order, starting from 0.0), then clamps it
inside the walls (x and y separately). A pair of movable robots
share a push half and half; a robot that stands still is not moved and the
other takes the whole push; carriers (present, not carried) are fixed
obstacles, except the one a robot is under (docking or driving out). A
loaded robot's body is its carrier's square. Pushing out along the contact
normal keeps the tangential part of the move: robots slide along what they
touch.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from swarmtag.sim._index import STILL_MODES, at_robots, in_modes, is_loaded
from swarmtag.sim.geometry import (
    FACE_NORMALS,
    Float,
    contact_push,
    contact_xy,
    length,
    step_towards,
    turn_towards,
)
from swarmtag.sim.params import Params
from swarmtag.sim.state import Int, Mode, WorldState

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
    centre = at_robots(s.carrier_pos, s.target)
    normal = FACE_NORMALS[np.maximum(s.face, 0)]
    predock = centre + normal * params.predock_offset
    goal = np.where(
        (mode == Mode.PREDOCK)[..., None],
        predock,
        np.where((mode == Mode.DOCK)[..., None], centre, s.goal),
    )
    driving = in_modes(mode, (Mode.PREDOCK, Mode.DOCK, Mode.TRANSPORT))
    sidestepping = (mode == Mode.TRANSPORT) & (s.sidestep > 0)
    towards = step_towards(pos, goal, speed)
    walked = pos + s.walk * speed[..., None]
    sidestep = pos + s.sidestep_dir * speed[..., None]
    proposed = np.where(
        (mode == Mode.WALK)[..., None],
        walked,
        np.where(sidestepping[..., None], sidestep, np.where(driving[..., None], towards, pos)),
    )
    s.sidestep[sidestepping] -= 1

    travel = proposed - pos
    distance = length(travel)
    safe = np.where(distance > 0, distance, 1.0)
    direction = travel / safe[..., None]
    facing = np.where(
        (mode == Mode.PREDOCK)[..., None],
        -normal,
        np.where((mode == Mode.WALK)[..., None], s.walk, direction),
    )
    turning = (
        (mode == Mode.PREDOCK) | (mode == Mode.WALK) | ((mode == Mode.TRANSPORT) & (distance > 0))
    )
    if turning.any():
        turned = turn_towards(s.heading, facing, params.turn_cos, params.turn_sin)
        np.copyto(s.heading, turned, where=turning[..., None])
    return proposed


@dataclass(frozen=True, eq=False)
class _Bodies:
    """What one tick's collision passes need, computed once per tick."""

    pair_extent: Float
    pair_radius: Float
    share: Float
    """(R, N, N) fraction of a robot-robot push that robot i takes."""
    tie: Float
    obstacle: NDArray[np.bool_]
    """(R, N, C) carriers that block each robot."""
    carrier_x: Float
    carrier_y: Float
    carrier_extent: Float
    carrier_radius: Float
    margin: Float
    arena: float


def _bodies(s: WorldState, params: Params) -> _Bodies:
    robots = s.mode.shape[1]
    extent, radius = body_shape(s.mode, s.target, params)
    movable = ~in_modes(s.mode, STILL_MODES)
    share = np.where(
        movable[:, :, None] & movable[:, None, :], 0.5, np.where(movable[:, :, None], 1.0, 0.0)
    )
    share[:, np.arange(robots), np.arange(robots)] = 0.0
    index = np.arange(robots)
    carriers = np.arange(s.carrier_pos.shape[1])
    obstacle = (s.present & (s.carried_by < 0))[:, None, :] & (carriers != s.ghost[..., None])
    shape = obstacle.shape
    carrier_extent = np.broadcast_to(extent[..., None] + params.carrier_half, shape)
    return _Bodies(
        pair_extent=extent[:, :, None] + extent[:, None, :],
        pair_radius=radius[:, :, None] + radius[:, None, :],
        share=share,
        tie=np.where(index[:, None] < index[None, :], -1.0, 1.0),
        obstacle=obstacle & movable[..., None],
        carrier_x=s.carrier_pos[..., 0],
        carrier_y=s.carrier_pos[..., 1],
        carrier_extent=carrier_extent,
        carrier_radius=np.broadcast_to(radius[..., None], shape),
        margin=extent + radius,
        arena=params.arena,
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


def _collision_pass(x: Float, y: Float, b: _Bodies) -> tuple[Float, Float, bool]:
    """One Jacobi pass; also says whether any pair was close enough to touch."""
    shape = x.shape
    dx = x[:, :, None] - x[:, None, :]
    dy = y[:, :, None] - y[:, None, :]
    reach = b.pair_extent + b.pair_radius
    near = (np.abs(dx) < reach) & (np.abs(dy) < reach) & (b.share > 0)
    runs, robots, others = np.nonzero(near)
    push_x, push_y, _ = contact_xy(
        dx[runs, robots, others],
        dy[runs, robots, others],
        b.pair_extent[runs, robots, others],
        b.pair_radius[runs, robots, others],
        b.tie[robots, others],
    )
    weight = b.share[runs, robots, others]
    robot_x, robot_y = _summed(runs, robots, shape, push_x * weight, push_y * weight)

    cx = x[:, :, None] - b.carrier_x[:, None, :]
    cy = y[:, :, None] - b.carrier_y[:, None, :]
    reach = b.carrier_extent + b.carrier_radius
    close = (np.abs(cx) < reach) & (np.abs(cy) < reach) & b.obstacle
    runs_c, robots_c, carriers = np.nonzero(close)
    push_x, push_y, _ = contact_xy(
        cx[runs_c, robots_c, carriers],
        cy[runs_c, robots_c, carriers],
        b.carrier_extent[runs_c, robots_c, carriers],
        b.carrier_radius[runs_c, robots_c, carriers],
        1.0,
    )
    carrier_x, carrier_y = _summed(runs_c, robots_c, shape, push_x, push_y)
    new_x = (x + robot_x) + carrier_x
    new_y = (y + robot_y) + carrier_y
    high = b.arena - b.margin
    new_x = np.minimum(np.maximum(new_x, b.margin), high)
    new_y = np.minimum(np.maximum(new_y, b.margin), high)
    return new_x, new_y, bool(runs.size or runs_c.size)


def resolve(s: WorldState, proposed: Float, params: Params) -> None:
    """Resolve collisions of the ``proposed`` positions and write the outcome into ``s``.

    Sets positions, the contact push, the positions of carried carriers, and
    forgets the carrier a robot was under once it is clear of it.
    A pass in which no pair is close enough to touch and the walls move
    nobody changes nothing, so the remaining passes are skipped.
    """
    bodies = _bodies(s, params)
    x, y = proposed[..., 0], proposed[..., 1]
    for _ in range(params.collision_iterations):
        new_x, new_y, touching = _collision_pass(x, y, bodies)
        settled = not touching and np.array_equal(new_x, x) and np.array_equal(new_y, y)
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
        extent, radius = body_shape(s.mode, s.target, params)
        _, depth = contact_push(offset, extent + params.carrier_half, radius, 1.0)
        clear = under & (depth <= 0) & ~in_modes(s.mode, (Mode.DOCK, Mode.CENTRE))
        s.ghost[clear] = -1
