"""The warehouse floor, compiled: ``floor_motion`` for one body or point.

Each function repeats its reference's operations in the same order
(``keep_off_shelves``: the four clamps, then the diagonal corners in
``floor_motion.DIAGONALS`` order), so the floats are the same.
"""

from __future__ import annotations

import math

from swarmtag.sim.fast._geometry import contact, maximum, minimum, segment_crosses_box
from swarmtag.sim.fast._jit import inlined
from swarmtag.sim.fast._layout import Constants, World

__all__ = [
    "cell_of",
    "clear_of_shelves",
    "hidden_by_shelves",
    "in_dropoff",
    "inside_area",
    "keep_off_shelves",
    "waypoint_of",
]


@inlined
def _index(scaled: float, size: int) -> int:
    """``floor_map._clipped_index`` for one value."""
    if math.isnan(scaled):
        return 0
    return int(min(max(math.floor(scaled), 0.0), float(size - 1)))


@inlined
def cell_of(px: float, py: float, k: Constants) -> tuple[int, int]:
    """The (row, column) of the cell holding (px, py), clipped into the map."""
    return _index(py / k.floor_cell, k.floor_rows), _index(px / k.floor_cell, k.floor_cols)


@inlined
def keep_off_shelves(
    px: float, py: float, extent: float, radius: float, row: int, col: int, k: Constants
) -> tuple[float, float]:
    """``floor_motion.keep_off_shelves`` for one body that started the tick in (row, col)."""
    blocked = k.floor_blocked
    cell = k.floor_cell
    margin = extent + radius
    pr = row + 1
    pc = col + 1
    if blocked[pr, pc - 1]:
        px = maximum(px, col * cell + margin)
    if blocked[pr, pc + 1]:
        px = minimum(px, (col + 1) * cell - margin)
    if blocked[pr - 1, pc]:
        py = maximum(py, row * cell + margin)
    if blocked[pr + 1, pc]:
        py = minimum(py, (row + 1) * cell - margin)
    half = 0.5 * cell
    for corner in range(4):
        dr = -1 if corner < 2 else 1
        dc = -1 if corner % 2 == 0 else 1
        if blocked[pr + dr, pc + dc] and not blocked[pr, pc + dc] and not blocked[pr + dr, pc]:
            centre_x = (col + dc) * cell + half
            centre_y = (row + dr) * cell + half
            push_x, push_y, _ = contact(px - centre_x, py - centre_y, extent + half, radius, 1.0)
            px = px + push_x
            py = py + push_y
    return px, py


@inlined
def clear_of_shelves(px: float, py: float, margin: float, k: Constants) -> bool:
    """``floor_motion.clear_of_shelves`` for one point."""
    inside = margin <= px <= k.arena - margin and margin <= py <= k.arena_height - margin
    row, col = cell_of(px, py, k)
    if not inside or k.floor_blocked[row + 1, col + 1]:
        return False
    kept_x, kept_y = keep_off_shelves(px, py, 0.0, margin, row, col, k)
    clear: bool = kept_x == px and kept_y == py
    return clear


@inlined
def inside_area(px: float, py: float, half: float, area: int, k: Constants) -> bool:
    """``floor_motion.inside_area``: the square of half-side ``half`` lies in area ``area``."""
    for corner in range(4):
        sx = -half if corner < 2 else half
        sy = -half if corner % 2 == 0 else half
        row, col = cell_of(px + sx, py + sy, k)
        if k.floor_area[row, col] != area:
            return False
    return True


@inlined
def in_dropoff(r: int, n: int, c: int, w: World, k: Constants) -> bool:
    """``_index.in_dropoff`` for robot ``n`` holding carrier ``c``."""
    px = w.robot_pos[r, n, 0]
    if not k.has_floor:
        inside: bool = px - k.carrier_half >= k.dropoff_left
        return inside
    area = k.floor_destinations[w.destination[r, max(c, 0)]]
    return inside_area(px, w.robot_pos[r, n, 1], k.carrier_half, area, k)


@inlined
def waypoint_of(px: float, py: float, destination: int, k: Constants) -> tuple[float, float]:
    """``floor_motion.transport_waypoints`` for one robot."""
    row, col = cell_of(px, py, k)
    return k.floor_waypoint[destination, row, col, 0], k.floor_waypoint[destination, row, col, 1]


@inlined
def hidden_by_shelves(sx: float, sy: float, ex: float, ey: float, k: Constants) -> bool:
    """``floor_motion.hidden_by_shelves`` for one sight line."""
    row0, col0 = cell_of(sx, sy, k)
    row1, col1 = cell_of(ex, ey, k)
    cell = k.floor_cell
    half = 0.5 * cell
    for row in range(min(row0, row1), max(row0, row1) + 1):
        for col in range(min(col0, col1), max(col0, col1) + 1):
            if k.floor_blocked[row + 1, col + 1] and segment_crosses_box(
                sx, sy, ex, ey, (col + 0.5) * cell, (row + 0.5) * cell, half
            ):
                return True
    return False
