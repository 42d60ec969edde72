"""Where a robot stands before docking: predock points and which of them are usable.

Each carrier has four predock points, one in front of each face (east,
north, west, south) at ``predock_offset`` from its centre. A point is usable
("free") when a robot standing there is inside the arena (in a warehouse:
off every shelf) and overlaps no other carrier that is an obstacle. A robot
docks at the free face whose predock point is nearest to it (ties: face
order); a carrier with no free face cannot be selected until a neighbour
leaves. With
``motion.avoid_taken_faces`` a face is also passed over while the robot
sees another robot standing on its point (``taken_faces``).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from swarmtag.sim.model.geometry import FACE_NORMALS, Float, contact_depth, length
from swarmtag.sim.model.params import Params
from swarmtag.sim.world.broad_phase import build_grid, grid_pays, near_points
from swarmtag.sim.world.floor import clear_of_shelves

__all__ = ["free_faces", "nearest_free_face", "predock_points", "taken_faces"]


def predock_points(carrier_pos: Float, offset: float) -> Float:
    """The four predock points of carriers at ``carrier_pos`` (shape ``(..., 4, 2)``).

    >>> predock_points(np.array([1.0, 2.0]), 0.5)
    array([[1.5, 2. ],
           [1. , 2.5],
           [0.5, 2. ],
           [1. , 1.5]])
    """
    return carrier_pos[..., None, :] + FACE_NORMALS * offset


def free_faces(
    carrier_pos: Float, obstacle: NDArray[np.bool_], params: Params
) -> NDArray[np.bool_]:
    """Which predock points are usable, shape ``(runs, carriers, 4)``.

    ``obstacle`` ``(runs, carriers)`` marks carriers that block a robot
    (present and not carried). Many carriers: only those near each point
    are tested (``swarmtag.sim.world.broad_phase``; the same result).
    """
    points = predock_points(carrier_pos, params.predock_offset)  # (R, C, 4, 2)
    if params.floor is None:
        low, high = params.robot_radius, params.arena - params.robot_radius
        inside = np.all((points >= low) & (points <= high), axis=-1)
    else:
        inside = clear_of_shelves(points[..., 0], points[..., 1], params.robot_radius, params.floor)
    runs, carriers = obstacle.shape
    if grid_pays("free", runs * carriers * 4, carriers):
        blocked = _blocked_points(points, carrier_pos, obstacle, params)
    else:
        offset = points[:, :, :, None, :] - carrier_pos[:, None, None, :, :]  # (R, C, 4, C', 2)
        extent = np.full(offset.shape[:-1], params.carrier_half)
        radius = np.full(offset.shape[:-1], params.robot_radius)
        depth = contact_depth(offset[..., 0], offset[..., 1], extent, radius)
        others = ~np.eye(carriers, dtype=bool)[None, :, None, :]
        blocked = np.any((depth > 0) & obstacle[:, None, None, :] & others, axis=-1)
    free: NDArray[np.bool_] = np.logical_and(inside, np.logical_not(blocked))
    return free


def _blocked_points(
    points: Float, carrier_pos: Float, obstacle: NDArray[np.bool_], params: Params
) -> NDArray[np.bool_]:
    """(R, C, 4): predock points a robot standing on would overlap another obstacle (grid).

    An overlap (positive depth of a robot's disc against the carrier's
    square) needs ``|dx|`` and ``|dy|`` under ``carrier_half + robot_radius``.
    """
    runs, carriers = obstacle.shape
    reach = params.carrier_half + params.robot_radius
    grid = build_grid(carrier_pos[..., 0], carrier_pos[..., 1], obstacle, reach)
    flat = points.reshape(runs, carriers * 4, 2)
    everyone = np.ones(flat.shape[:2], dtype=bool)
    rows, point, other = near_points(grid, flat[..., 0], flat[..., 1], everyone, reach)
    carrier, face = point // 4, point % 4
    dx = points[rows, carrier, face, 0] - carrier_pos[rows, other, 0]
    dy = points[rows, carrier, face, 1] - carrier_pos[rows, other, 1]
    extent = np.full(dx.shape, params.carrier_half)
    radius = np.full(dx.shape, params.robot_radius)
    depth = contact_depth(dx, dy, extent, radius)
    hit = (depth > 0) & (other != carrier)
    blocked = np.zeros((runs, carriers, 4), dtype=bool)
    blocked[rows[hit], carrier[hit], face[hit]] = True
    return blocked


def nearest_free_face(
    robot_pos: Float, carrier_pos: Float, free: NDArray[np.bool_], offset: float
) -> NDArray[np.int64]:
    """Index of the free face whose predock point is nearest each robot, -1 if none is free.

    ``robot_pos`` and ``carrier_pos`` have the same leading shape (a robot
    and the carrier it chose); ``free`` adds the face axis.
    """
    distance = length(predock_points(carrier_pos, offset) - robot_pos[..., None, :])
    distance = np.where(free, distance, np.inf)
    face = np.argmin(distance, axis=-1).astype(np.int64)
    return np.where(free.any(axis=-1), face, -1)


def taken_faces(
    robot_pos: Float,
    carrier_pos: Float,
    offset: float,
    *,
    body: float,
    sight: float,
    asking: NDArray[np.bool_] | None = None,
) -> NDArray[np.bool_]:
    """Which predock points of each robot's carrier it sees taken by another robot, (R, N, 4).

    ``carrier_pos`` (R, N, 2) is each robot's carrier. Point f is taken for
    robot n when another robot m stands within ``body`` (one diameter) of it,
    nearer to it than n, and within ``sight`` of n (it can see m). Only the
    robots in ``asking`` (R, N) (default: all) are answered; the others get
    False. Many robots: only those near each point are tested
    (``swarmtag.sim.world.broad_phase``; the same result).
    """
    runs, robots = robot_pos.shape[:2]
    if asking is None:
        asking = np.ones((runs, robots), dtype=bool)
    points = predock_points(carrier_pos, offset)  # (R, N, 4, 2)
    taken = np.zeros((runs, robots, 4), dtype=bool)
    if grid_pays("taken", int(np.count_nonzero(asking)) * 4, robots):
        grid = build_grid(robot_pos[..., 0], robot_pos[..., 1], np.ones_like(asking), body)
        flat = points.reshape(runs, robots * 4, 2)
        rows, point, other = near_points(
            grid, flat[..., 0], flat[..., 1], np.repeat(asking, 4, axis=1), body
        )
        robot, face = point // 4, point % 4
        at = points[rows, robot, face]
        me = robot_pos[rows, robot]
        gap = length(robot_pos[rows, other] - at)
        mine = length(me - at)
        apart = length(me - robot_pos[rows, other])
        hit = (gap < body) & (gap < mine) & (apart <= sight) & (other != robot)
        taken[rows[hit], robot[hit], face[hit]] = True
        return taken
    rows, ids = np.nonzero(asking)
    mine_points = points[rows, ids]  # (K, 4, 2)
    me = robot_pos[rows, ids]  # (K, 2)
    others = robot_pos[rows]  # (K, M, 2)
    gap = length(others[:, None, :, :] - mine_points[:, :, None, :])  # (K, 4, M)
    mine = length(me[:, None, :] - mine_points)  # (K, 4)
    apart = length(me[:, None, :] - others)  # (K, M)
    other = (np.arange(robots)[None, :] != ids[:, None])[:, None, :]
    seen = (apart <= sight)[:, None, :]
    taken[rows, ids] = np.any((gap < body) & (gap < mine[..., None]) & seen & other, axis=-1)
    return taken
