"""How a warehouse floor acts on bodies: shelves stop them, areas take deliveries, paths lead.

Pure batched functions of positions and a ``FloorMap`` (the lab arena has
none and never calls them):

- ``keep_off_shelves``: like the walls, shelves are kept out by clamping, x
  and y separately, against the shelf cells beside the cell the robot
  started the tick in; a shelf cell diagonal to it (both cells between them
  free) pushes the body out of its corner like a carrier does
  (``geometry.contact_xy``). A body narrower than half a cell can touch at
  most one such corner, so the result does not depend on an order of sums.
- ``clear_of_shelves``: whether a body at a point stays off every shelf (a
  predock point behind a shelf is not a usable face).
- ``inside_area``: a carrier lies wholly inside its destination's drop-off
  cells (its four corners are).
- ``hidden_by_shelves``: shelves hide carriers from the camera (a sight
  line through a shelf cell is blocked) wherever occlusion is on;
- ``transport_waypoints``: where a loaded robot drives next: the centre of
  the next cell on a shortest path to its destination area
  (``FloorMap.waypoint``).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from swarmtag.sim.config.floor_map import FloorMap
from swarmtag.sim.model.geometry import Float, contact_xy, segment_crosses_box

__all__ = [
    "DIAGONALS",
    "cells_of",
    "clear_of_shelves",
    "hidden_by_shelves",
    "inside_area",
    "keep_off_shelves",
    "transport_waypoints",
]

Int = NDArray[np.int64]

DIAGONALS: tuple[tuple[int, int], ...] = ((-1, -1), (-1, 1), (1, -1), (1, 1))
"""(row, column) steps to the four diagonal neighbours, in the order their pushes apply."""


def cells_of(floor: FloorMap, position: Float) -> tuple[Int, Int]:
    """The (row, column) of the cell each position (..., 2) lies in (``FloorMap.cell_of``)."""
    return floor.cell_of(position[..., 0], position[..., 1])


def keep_off_shelves(
    x: Float,
    y: Float,
    *,
    extent: Float,
    radius: Float,
    row: Int,
    col: Int,
    floor: FloorMap,
) -> tuple[Float, Float]:
    """Positions moved off the shelves around cell (``row``, ``col``) (see the module docs)."""
    blocked, cell = floor.blocked, floor.cell
    margin = extent + radius
    pr, pc = row + 1, col + 1
    x = np.where(blocked[pr, pc - 1], np.maximum(x, col * cell + margin), x)
    x = np.where(blocked[pr, pc + 1], np.minimum(x, (col + 1) * cell - margin), x)
    y = np.where(blocked[pr - 1, pc], np.maximum(y, row * cell + margin), y)
    y = np.where(blocked[pr + 1, pc], np.minimum(y, (row + 1) * cell - margin), y)
    half = 0.5 * cell
    for dr, dc in DIAGONALS:
        corner = blocked[pr + dr, pc + dc] & ~blocked[pr, pc + dc] & ~blocked[pr + dr, pc]
        if not corner.any():
            continue
        centre_x = (col + dc) * cell + half
        centre_y = (row + dr) * cell + half
        push_x, push_y, _ = contact_xy(x - centre_x, y - centre_y, extent + half, radius, 1.0)
        x = np.where(corner, x + push_x, x)
        y = np.where(corner, y + push_y, y)
    return x, y


def clear_of_shelves(x: Float, y: Float, margin: float, floor: FloorMap) -> NDArray[np.bool_]:
    """Whether a body of half-size ``margin`` at (x, y) stands off every shelf and wall."""
    inside = (x >= margin) & (x <= floor.width - margin)
    inside &= (y >= margin) & (y <= floor.height - margin)
    row, col = floor.cell_of(x, y)
    free = ~floor.blocked[row + 1, col + 1]
    kept_x, kept_y = keep_off_shelves(
        x,
        y,
        extent=np.zeros(np.shape(x)),
        radius=np.full(np.shape(x), margin),
        row=row,
        col=col,
        floor=floor,
    )
    clear: NDArray[np.bool_] = inside & free & (kept_x == x) & (kept_y == y)
    return clear


def inside_area(x: Float, y: Float, half: float, area: Int, floor: FloorMap) -> NDArray[np.bool_]:
    """Whether the square of half-side ``half`` at (x, y) lies in drop-off area id ``area``."""
    inside = np.ones(np.shape(x), dtype=bool)
    for sx in (-half, half):
        for sy in (-half, half):
            row, col = floor.cell_of(x + sx, y + sy)
            inside &= floor.area[row, col] == area
    return inside


def hidden_by_shelves(start: Float, end: Float, floor: FloorMap) -> NDArray[np.bool_]:
    """(K,): sight lines ``start``-``end`` (K, 2) that pass through a shelf cell.

    The cells tested are those of the segment's bounding box; a line that
    only grazes a shelf's edge or corner is not blocked (the open square of
    ``geometry.segment_crosses_box``).
    """
    row0, col0 = cells_of(floor, start)
    row1, col1 = cells_of(floor, end)
    low_row, high_row = np.minimum(row0, row1), np.maximum(row0, row1)
    low_col, high_col = np.minimum(col0, col1), np.maximum(col0, col1)
    if start.shape[0] == 0:
        return np.zeros(0, dtype=bool)
    span = int(max((high_row - low_row).max(), (high_col - low_col).max())) + 1
    steps = np.arange(span)
    rows = low_row[:, None, None] + steps[None, :, None]  # (K, S, 1)
    cols = low_col[:, None, None] + steps[None, None, :]  # (K, 1, S)
    inside = (rows <= high_row[:, None, None]) & (cols <= high_col[:, None, None])
    blocked = floor.blocked[np.minimum(rows, floor.rows) + 1, np.minimum(cols, floor.cols) + 1]
    shelf = inside & blocked
    centre = np.stack(np.broadcast_arrays((cols + 0.5) * floor.cell, (rows + 0.5) * floor.cell), -1)
    crosses = segment_crosses_box(
        start[:, None, None, :], end[:, None, None, :], centre, 0.5 * floor.cell
    )
    hidden: NDArray[np.bool_] = (crosses & shelf).any(axis=(1, 2))
    return hidden


def transport_waypoints(position: Float, destination: Int, floor: FloorMap) -> Float:
    """The next waypoint (..., 2) of robots at ``position`` going to ``destination`` (an index)."""
    row, col = cells_of(floor, position)
    waypoint: Float = floor.waypoint[destination, row, col]
    return waypoint
