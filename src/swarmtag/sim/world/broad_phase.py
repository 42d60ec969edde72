"""Broad phase of the reference kernel: uniform grids that find the pairs worth an exact test.

The kernel's pairwise tests (collisions, free and taken predock faces, the
camera's line of sight) need only the pairs of bodies near each other. A
``Grid`` bins the points of every run of a batch into square cells at once
(a counting sort: ``np.bincount`` of the cell keys, its ``cumsum`` as the
start of each cell, the points in cell order by a stable sort), so that
the points inside any axis-aligned box are read from a few contiguous
slices, one per row of cells the box covers. The cost per query is flat
however many bodies the arena holds; dense all-pairs arrays cost O(N) per
query and win only for small swarms (``grid_pays``).

**Nothing is lost.** A cell index is ``clip(floor((v - origin) / side), 0,
width - 1)`` of a coordinate ``v``: every step is monotone in ``v`` (a
floating-point subtraction, a division by a positive number, ``floor`` and
``clip`` never reverse an order), so a point whose coordinates lie in
``[lo, hi]`` always has its cell between the cells of ``lo`` and ``hi``,
whatever the rounding, the cell size or the clamping of the grid to its
width (points beyond the arena's walls land in the edge cells). A query
box is the body's reach around it, grown by ``padding``: more than any
rounding of the exact tests' few operations can add to a distance (a
relative 2**-20 of the reach and 2**-30 of the largest coordinate, where
rounding moves a result by about 2**-53 of it per operation). So every
pair an exact test accepts is among the candidates; the caller runs the
exact test, written as in the dense code, on the candidates, and sorts the
pairs it keeps where an order matters (sums over partners in index order).
Points with a coordinate that is not finite are left out of grids and
queries; the exact tests reject them too (every comparison with NaN is
false, and no finite reach exceeds an infinite distance).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Final

import numpy as np
from numpy.typing import NDArray

from swarmtag.sim.model.geometry import Float

__all__ = [
    "GRID_FROM",
    "Grid",
    "build_grid",
    "first_claims",
    "grid_pays",
    "near_points",
    "near_segments",
    "padding",
    "sorted_pairs",
]

Int = NDArray[np.int64]

GRID_FROM: Final = {
    "robots": (40, 25_000),
    "obstacles": (16, 20_000),
    "taken": (10, 50_000),
    "free": (1, 5_000),
    "sight": (32, 50_000),
}
"""Per pairwise test: (partners, pairs) from which it uses a grid rather than dense arrays.

A test uses a grid when each query has at least ``partners`` bodies to be
tested against and the dense arrays would hold at least ``pairs`` pairs
(over the batch): below either, building the grid costs more than it
saves. ``robots``: collisions between robots (a grid per pass);
``obstacles``: robots against carriers (one grid per tick); ``taken``:
predock points against robots; ``free``: predock points against carriers;
``sight``: lines of sight against carriers, and against robots. Measured
on two cores (docs/simulator.md, Performance). A dict, so that tests can
force either path.
"""

CELLS_PER_POINT: Final = 4
"""A grid has at most this many cells per point of a run (larger cells beyond)."""


def grid_pays(test: str, queries: int, partners: int) -> bool:
    """Whether ``test`` (a key of ``GRID_FROM``) of ``queries`` against ``partners`` uses a grid.

    ``queries`` counts over the whole batch, ``partners`` per run.
    """
    least_partners, least_pairs = GRID_FROM[test]
    return partners >= least_partners and queries * partners >= least_pairs


def padding(reach: float, scale: float) -> float:
    """Half-side of a query box: ``reach``, plus far more than rounding adds near ``scale``."""
    return reach * (1.0 + 2.0**-20) + 2.0**-30 * (1.0 + scale)


@dataclass(frozen=True, eq=False)
class Grid:
    """Points of every run of a batch, binned into ``width`` x ``width`` square cells."""

    width: int
    """Cells per side."""
    origin_x: float
    origin_y: float
    side: float
    """Cell side, metres."""
    scale: float
    """The largest magnitude of a binned coordinate (for ``padding``)."""
    start: Int
    """(R * width * width + 1,) where each cell's points begin in ``order``.

    Cells are numbered by run, then row (y), then column (x).
    """
    order: Int
    """Index of each binned point within its run, in cell order (a cell's points in index order)."""


def _cell(value: Float, origin: float, side: float, width: int) -> Int:
    """Cell index of each coordinate: monotone in ``value``, clamped to the grid."""
    cell: Int = np.clip(np.floor((value - origin) / side), 0, width - 1).astype(np.int64)
    return cell


def _finite(x: Float, y: Float) -> NDArray[np.bool_]:
    finite: NDArray[np.bool_] = np.isfinite(x) & np.isfinite(y)
    return finite


def _largest(*values: Float) -> float:
    """The largest magnitude among ``values`` (0 when all are empty)."""
    return max((float(np.max(np.abs(v))) for v in values if v.size), default=0.0)


def build_grid(x: Float, y: Float, valid: NDArray[np.bool_], side: float) -> Grid:
    """Bin the ``valid`` points (R, P) of every run into square cells of at least ``side`` metres.

    The grid spans the points binned (over all runs). Its cells are made
    larger where the span would need more than ``CELLS_PER_POINT`` cells per
    point of a run: counting every cell costs time too.
    """
    runs, points = x.shape
    rows, index = np.nonzero(valid & _finite(x, y))
    px, py = x[rows, index], y[rows, index]
    if px.size == 0:
        return Grid(1, 0.0, 0.0, side, 0.0, np.zeros(runs + 1, dtype=np.int64), index)
    origin_x, origin_y = float(px.min()), float(py.min())
    span = max(float(px.max()) - origin_x, float(py.max()) - origin_y)
    most = max(2, math.isqrt(CELLS_PER_POINT * points))
    side = max(side, span / (most - 1))
    width = min(int(span // side) + 1, most)
    cx = _cell(px, origin_x, side, width)
    cy = _cell(py, origin_y, side, width)
    key = (rows * width + cy) * width + cx
    counts = np.bincount(key, minlength=runs * width * width)
    start = np.concatenate((np.zeros(1, dtype=np.int64), np.cumsum(counts)))
    order = index[np.argsort(key, kind="stable")]
    return Grid(width, origin_x, origin_y, side, _largest(px, py), start, order)


def _expand(counts: Int) -> tuple[Int, Int]:
    """For each i, ``counts[i]`` entries: their owner i and their rank 0 .. counts[i] - 1."""
    owner = np.repeat(np.arange(counts.size), counts)
    first = np.cumsum(counts) - counts
    rank: Int = np.arange(owner.size) - first[owner]
    return owner, rank


def _in_boxes(grid: Grid, runs: Int, box: tuple[Float, Float, Float, Float]) -> tuple[Int, Int]:
    """(query, point): every binned point of run ``runs[q]`` in a cell that box q touches.

    ``box`` is (low x, high x, low y, high y), one per query. The cells a
    box touches form a rectangle; each of its rows is one slice of
    ``grid.order``.
    """
    low_x, high_x, low_y, high_y = box
    x0 = _cell(low_x, grid.origin_x, grid.side, grid.width)
    x1 = _cell(high_x, grid.origin_x, grid.side, grid.width)
    y0 = _cell(low_y, grid.origin_y, grid.side, grid.width)
    y1 = _cell(high_y, grid.origin_y, grid.side, grid.width)
    owner, rank = _expand(y1 - y0 + 1)
    row = (runs[owner] * grid.width + y0[owner] + rank) * grid.width
    begin = grid.start[row + x0[owner]]
    end = grid.start[row + x1[owner] + 1]
    which, offset = _expand(end - begin)
    point: Int = grid.order[begin[which] + offset]
    query: Int = owner[which]
    return query, point


def near_points(
    grid: Grid, x: Float, y: Float, asking: NDArray[np.bool_], reach: float
) -> tuple[Int, Int, Int]:
    """Candidate pairs (run, query, point): the binned points within ``reach`` of each query point.

    ``x``, ``y`` and ``asking`` are (R, Q). Includes every pair with
    ``|dx| < reach`` and ``|dy| < reach`` as the exact tests compute them
    (``dx`` the difference of the two x, rounded), and others: the caller
    tests each candidate exactly. No order.
    """
    runs, queries = np.nonzero(asking & _finite(x, y))
    qx, qy = x[runs, queries], y[runs, queries]
    if qx.size == 0 or grid.order.size == 0:
        empty = np.zeros(0, dtype=np.int64)
        return empty, empty, empty
    pad = padding(reach, max(grid.scale, _largest(qx, qy)))
    which, point = _in_boxes(grid, runs, (qx - pad, qx + pad, qy - pad, qy + pad))
    return runs[which], queries[which], point


def near_segments(grid: Grid, runs: Int, start: Float, end: Float, reach: float) -> tuple[Int, Int]:
    """Candidate pairs (segment, point): the binned points within ``reach`` of each segment's box.

    ``start`` and ``end`` are (K, 2), segment k lying in run ``runs[k]``.
    Includes every point within ``reach`` of the axis-aligned box around
    its segment, so every point closer than ``reach`` to the segment, and
    every box centre whose square of half-side ``reach`` the segment
    crosses. No order.
    """
    finite = _finite(start[:, 0], start[:, 1]) & _finite(end[:, 0], end[:, 1])
    (keep,) = np.nonzero(finite)
    if keep.size == 0 or grid.order.size == 0:
        empty = np.zeros(0, dtype=np.int64)
        return empty, empty
    sx, sy, ex, ey = start[keep, 0], start[keep, 1], end[keep, 0], end[keep, 1]
    pad = padding(reach, max(grid.scale, _largest(sx, sy, ex, ey)))
    box = (
        np.minimum(sx, ex) - pad,
        np.maximum(sx, ex) + pad,
        np.minimum(sy, ey) - pad,
        np.maximum(sy, ey) + pad,
    )
    which, point = _in_boxes(grid, runs[keep], box)
    return keep[which], point


def sorted_pairs(
    runs: Int, queries: Int, points: Int, shape: tuple[int, int, int]
) -> tuple[Int, Int, Int]:
    """The pairs in ``np.nonzero`` order of a dense (R, Q, P) mask: by run, query, then point."""
    key = (runs * shape[1] + queries) * shape[2] + points
    order = np.argsort(key)
    return runs[order], queries[order], points[order]


def first_claims(claim: NDArray[np.bool_], key: Int, keys: int) -> NDArray[np.bool_]:
    """``claim`` (R, N) where no smaller index of the run claims the same ``key`` (0 .. keys - 1).

    The smallest id wins: in O(N) per run (the smallest claimant of each
    key by ``np.minimum.at``) instead of comparing every pair of robots.
    """
    runs, robots = claim.shape
    rows, ids = np.nonzero(claim)
    smallest = np.full((runs, keys), robots, dtype=np.int64)
    np.minimum.at(smallest, (rows, key[rows, ids]), ids)
    mine = smallest[np.arange(runs)[:, None], np.clip(key, 0, keys - 1)]
    first: NDArray[np.bool_] = claim & (mine == np.arange(robots)[None, :])
    return first
