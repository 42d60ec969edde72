"""The folded grid's queries against every point: nothing in reach is left out, order kept."""

import math

import numba
import numpy as np
import pytest

from swarmtag.sim.fast._grid import fill, near, near_within


@numba.njit(cache=False)  # not cached: machine code cached here would keep old grid code
def _queries(
    inputs: tuple[np.ndarray, np.ndarray, np.ndarray],
    shape: tuple[float, float, int, bool],
    grid: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray],
    found: np.ndarray,
) -> None:
    """Grid the points (run 0), then ``near`` and ``near_within`` at every query point.

    ``inputs``: the points' x and y (``(1, points)``) and the queries
    (``(queries, 2)``); ``shape``: reach, cell, bits, ordered; ``grid``: the
    table's arrays (``start``, ``items``, ``keys``, ``item_at``, ``out``;
    compiled code allocates nothing). ``found[0, q, 0]`` is ``near``'s count
    and ``found[0, q, 1:]`` its points; ``found[1]`` the same for
    ``near_within`` (reach ``cell``).
    """
    xs, ys, queries = inputs
    reach, cell, bits, ordered = shape
    start, items, keys, item_at, out = grid
    count = xs.shape[1]
    fill(0, xs, ys, count, cell, bits, start, items, keys)
    for i in range(count):
        item_at[0, keys[0, i], 0] = xs[0, i]
        item_at[0, keys[0, i], 1] = ys[0, i]
    for q in range(queries.shape[0]):
        qx, qy = queries[q, 0], queries[q, 1]
        n = near(0, qx, qy, reach, cell, bits, start, items, out, ordered)
        found[0, q, 0] = n
        for j in range(n):
            found[0, q, j + 1] = out[0, j]
        n = near_within(0, qx, qy, cell, bits, start, items, item_at, out)
        found[1, q, 0] = n
        for j in range(n):
            found[1, q, j + 1] = out[0, j]


def _cells(at: float, reach: float, cell: float) -> range:
    """The cells along one axis that ``at +- reach`` touches."""
    inverse = 1.0 / cell  # the grid's map: a multiplication by the inverse
    return range(math.floor((at - reach) * inverse), math.floor((at + reach) * inverse) + 1)


@pytest.mark.parametrize(
    ("side", "bits", "reach_share", "cell"),
    [
        (3.0, 2, 1.0, 1.0),
        (40.0, 2, 0.6, 1.0),
        (40.0, 5, 1.0, 1.0),
        (200.0, 4, 0.3, 1.0),
        (15.0, 4, 1.0, 0.355),
    ],
    ids=["one-fold", "wrapping", "wide-table", "short-reach", "inexact-inverse"],
)
@pytest.mark.parametrize("ordered", [True, False], ids=["ordered", "unordered"])
def test_queries_find_every_point_in_reach_each_once(side, bits, reach_share, cell, ordered):
    # small tables on a wide arena: most rows of buckets wrap around the fold somewhere
    rng = np.random.default_rng(7)
    reach = reach_share * cell
    points = rng.random((2, 1, 300)) * side
    xs, ys = points[0], points[1]
    queries = rng.random((400, 2)) * side
    found = np.zeros((2, 400, 301), dtype=np.int64)
    grid = (
        np.zeros((1, (1 << (2 * bits)) + 1), dtype=np.int32),
        np.zeros((1, 300), dtype=np.int64),
        np.zeros((1, 300), dtype=np.int64),
        np.zeros((1, 300, 2)),
        np.zeros((1, 300), dtype=np.int64),
    )
    _queries((xs, ys, queries), (reach, cell, bits, ordered), grid, found)
    cells_x = np.floor(xs[0] * (1.0 / cell)).astype(np.int64)
    cells_y = np.floor(ys[0] * (1.0 / cell)).astype(np.int64)
    fold = (1 << bits) - 1
    for q, (qx, qy) in enumerate(queries):
        got = found[0, q, 1 : found[0, q, 0] + 1]
        # exactly the points of the buckets of the cells the reach square touches
        columns = {c & fold for c in _cells(qx, reach, cell)}
        rows = {c & fold for c in _cells(qy, reach, cell)}
        expected = [
            i for i in range(300) if cells_x[i] & fold in columns and cells_y[i] & fold in rows
        ]
        assert sorted(got.tolist()) == expected  # each point once
        if ordered:
            assert got.tolist() == expected
        within = found[1, q, 1 : found[1, q, 0] + 1].tolist()
        close = (np.abs(qx - xs[0]) < cell) & (np.abs(qy - ys[0]) < cell)
        assert within == np.flatnonzero(close).tolist()  # ascending, no far point of a fold


@pytest.mark.parametrize("cell", [1.0, 0.355, 0.1, 3.7])
def test_a_point_at_the_edge_of_the_reach_is_found(cell):
    # points on the cells' borders (and a rounding step either side), queries whose
    # reach ends there: where the cells' map rounds, a point the caller's test
    # accepts must still be found (a query mapped otherwise than the points misses some)
    reach = 0.8 * cell
    borders = np.arange(1, 60) * cell
    xs = np.concatenate([np.nextafter(borders, -np.inf), borders, np.nextafter(borders, np.inf)])
    ys = np.zeros_like(xs)
    starts = np.concatenate([borders + reach, borders - reach])
    queries = np.stack(
        [np.concatenate([starts, np.nextafter(starts, np.inf)]), np.zeros(4 * 59)], 1
    )
    points = xs.size
    found = np.zeros((2, len(queries), points + 1), dtype=np.int64)
    grid = (
        np.zeros((1, (1 << 8) + 1), dtype=np.int32),
        np.zeros((1, points), dtype=np.int64),
        np.zeros((1, points), dtype=np.int64),
        np.zeros((1, points, 2)),
        np.zeros((1, points), dtype=np.int64),
    )
    _queries((xs[None], ys[None], queries), (reach, cell, 4, True), grid, found)
    edge_points = 0
    for q, (qx, qy) in enumerate(queries):
        got = set(found[0, q, 1 : found[0, q, 0] + 1].tolist())
        accepted = np.flatnonzero((np.abs(qx - xs) < reach) & (np.abs(qy - ys) < reach))
        assert set(accepted.tolist()) <= got
        edge_points += len(accepted)
    assert edge_points > len(queries)  # most queries accept a point on a border
