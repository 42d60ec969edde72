"""Uniform grids (cell lists) for the compiled kernel: the nearby bodies, found in O(1).

A grid covers ``[0, columns * cell) x [0, rows * cell)`` with square cells
(coordinates outside go to the edge cells). ``fill`` sorts points into cells
by counting sort: cell ``k`` holds ``items[start[k] : start[k + 1]]``, in
ascending point order. ``near`` gathers, in ascending order, the points of
every cell the square ``position +- reach`` touches. Sums over bodies must
run in index order to match the reference bit for bit, so ``near`` returns
its points sorted; the caller then tests each one exactly as the reference
tests every pair, and a point the grid leaves out is one that test rejects.
"""

from __future__ import annotations

import math

import numpy as np

from swarmtag.sim.fast._jit import inlined

__all__ = ["fill", "near"]


@inlined
def _cell(value: float, cell: float, size: int) -> int:
    """The cell index of a coordinate, clamped to the grid."""
    index = math.floor(value / cell)
    return min(max(index, 0), size - 1)


@inlined
def fill(
    r: int,
    xs: np.ndarray,
    ys: np.ndarray,
    count: int,
    cell: float,
    columns: int,
    rows: int,
    start: np.ndarray,
    items: np.ndarray,
) -> None:
    """Sort points ``(xs[r, i], ys[r, i])``, ``i < count``, into run ``r``'s ``start``/``items``."""
    cells = columns * rows
    for k in range(cells + 1):
        start[r, k] = 0
    for i in range(count):
        start[r, _cell(xs[r, i], cell, columns) * rows + _cell(ys[r, i], cell, rows)] += 1
    for k in range(1, cells):  # inclusive prefix sums: the end of each cell
        start[r, k] += start[r, k - 1]
    start[r, cells] = count
    for i in range(count - 1, -1, -1):  # backwards: each cell ends up in ascending order
        k = _cell(xs[r, i], cell, columns) * rows + _cell(ys[r, i], cell, rows)
        start[r, k] -= 1
        items[r, start[r, k]] = i


@inlined
def near(
    r: int,
    x: float,
    y: float,
    reach: float,
    cell: float,
    columns: int,
    rows: int,
    start: np.ndarray,
    items: np.ndarray,
    out: np.ndarray,
    ordered: bool,
) -> int:
    """Points of run ``r`` in the cells within ``reach`` of ``(x, y)`` into ``out[r]``.

    ``ordered``: ascending (sums over bodies), else in cell order (tests whose
    answer does not depend on the order).
    """
    found = 0
    low_x = _cell(x - reach, cell, columns)
    high_x = _cell(x + reach, cell, columns)
    low_y = _cell(y - reach, cell, rows)
    high_y = _cell(y + reach, cell, rows)
    for gx in range(low_x, high_x + 1):
        for gy in range(low_y, high_y + 1):
            k = gx * rows + gy
            for slot in range(start[r, k], start[r, k + 1]):
                item = items[r, slot]
                position = found
                if ordered:  # insertion sort: the lists are short
                    while position > 0 and out[r, position - 1] > item:
                        out[r, position] = out[r, position - 1]
                        position -= 1
                out[r, position] = item
                found += 1
    return found
