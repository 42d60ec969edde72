"""Where a robot stands before docking: predock points and which of them are usable.

Each carrier has four predock points, one in front of each face (east,
north, west, south) at ``predock_offset`` from its centre. A point is usable
("free") when a robot standing there is inside the arena and overlaps no
other carrier that is an obstacle. A robot docks at the free face whose
predock point is nearest to it (ties: face order); a carrier with no free
face cannot be selected until a neighbour leaves. With
``motion.avoid_taken_faces`` a face is also passed over while the robot
sees another robot standing on its point (``taken_faces``).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from swarmtag.sim.geometry import FACE_NORMALS, Float, contact_push, length
from swarmtag.sim.params import Params

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
    (present and not carried).
    """
    points = predock_points(carrier_pos, params.predock_offset)  # (R, C, 4, 2)
    low, high = params.robot_radius, params.arena - params.robot_radius
    inside = np.all((points >= low) & (points <= high), axis=-1)
    offset = points[:, :, :, None, :] - carrier_pos[:, None, None, :, :]  # (R, C, 4, C', 2)
    extent = np.full(offset.shape[:-1], params.carrier_half)
    radius = np.full(offset.shape[:-1], params.robot_radius)
    _, depth = contact_push(offset, extent, radius, 1.0)
    carriers = carrier_pos.shape[1]
    others = ~np.eye(carriers, dtype=bool)[None, :, None, :]
    blocked = np.any((depth > 0) & obstacle[:, None, None, :] & others, axis=-1)
    free: NDArray[np.bool_] = np.logical_and(inside, np.logical_not(blocked))
    return free


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
    robot_pos: Float, carrier_pos: Float, offset: float, *, body: float, sight: float
) -> NDArray[np.bool_]:
    """Which predock points of each robot's carrier it sees taken by another robot, (R, N, 4).

    ``carrier_pos`` (R, N, 2) is each robot's carrier. Point f is taken for
    robot n when another robot m stands within ``body`` (one diameter) of it,
    nearer to it than n, and within ``sight`` of n (it can see m).
    """
    points = predock_points(carrier_pos, offset)  # (R, N, 4, 2)
    others = robot_pos[:, None, None, :, :]  # (R, 1, 1, M, 2)
    gap = length(others - points[:, :, :, None, :])  # (R, N, 4, M)
    mine = length(robot_pos[:, :, None, :] - points)  # (R, N, 4)
    apart = length(robot_pos[:, :, None, :] - robot_pos[:, None, :, :])  # (R, N, M)
    robots = robot_pos.shape[1]
    other = ~np.eye(robots, dtype=bool)[None, :, None, :]
    seen = (apart <= sight)[:, :, None, :]
    taken: NDArray[np.bool_] = np.any(
        (gap < body) & (gap < mine[..., None]) & seen & other, axis=-1
    )
    return taken
