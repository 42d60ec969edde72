"""Spatial hashing for the compiled kernel: the nearby bodies, found in O(1), in O(n) memory.

Space is cut into square cells of side ``cell``; a body at ``(x, y)`` is in
cell ``(floor(x * inverse), floor(y * inverse))`` with ``inverse = 1 / cell``
(a multiplication, not a division: about 6 ns less a query), and cells are folded onto a
table of ``2**bits`` by ``2**bits`` buckets (cell ``(ix, iy)`` goes to bucket
``(ix mod 2**bits, iy mod 2**bits)``; about twice as many buckets as
bodies), so that building and clearing cost O(bodies) however large the
arena. ``fill`` sorts points into buckets by counting sort: bucket ``b``
holds ``items[start[b] : start[b + 1]]``, in ascending point order. ``near``
gathers the points of the buckets of the cells the square ``position +-
reach`` touches: at most 3 by 3 cells (``reach <= cell``), which fall in 9
different buckets (``2**bits >= 4``). A bucket may also hold points of far
cells folded onto it: the caller tests every point it gets exactly as the
reference tests every pair, so extra points change nothing. A point left
out is one that test rejects: points and queries get their cells from one
map that keeps order (rounding is monotonic), so a point at or beyond
``x - reach`` as rounded falls in a cell at or beyond the query's first.
Sums over bodies must run in index order to match the reference bit for
bit, so ``near`` can return its points sorted.
"""

from __future__ import annotations

import math

import numpy as np

from swarmtag.sim.fast._jit import entry, inlined

__all__ = ["fill", "near", "near_within", "table_bits"]


@entry
def table_bits(bodies: int) -> int:
    """``bits`` of a table for ``bodies`` points: ``4**bits >= 2 * bodies``, at least 2."""
    bits = 2
    while 4**bits < 2 * bodies:
        bits += 1
    return bits


@inlined
def _bucket(ix: int, iy: int, bits: int) -> int:
    """The bucket of cell ``(ix, iy)``: both folded onto ``2**bits``."""
    fold = (1 << bits) - 1
    return (ix & fold) | ((iy & fold) << bits)


@inlined
def fill(
    r: int,
    xs: np.ndarray,
    ys: np.ndarray,
    count: int,
    cell: float,
    bits: int,
    start: np.ndarray,
    items: np.ndarray,
    keys: np.ndarray,
) -> None:
    """Sort points ``(xs[r, i], ys[r, i])``, ``i < count``, into run ``r``'s ``start``/``items``.

    ``keys[r, :count]`` is working space: each point's bucket, then its slot
    in ``items`` (``keys[r, items[r, slot]] == slot``).
    """
    buckets = 1 << (2 * bits)
    for b in range(buckets + 1):
        start[r, b] = 0
    inverse = 1.0 / cell
    for i in range(count):
        b = _bucket(math.floor(xs[r, i] * inverse), math.floor(ys[r, i] * inverse), bits)
        keys[r, i] = b
        start[r, b] += 1
    total = 0
    for b in range(buckets):  # inclusive prefix sums (the end of each bucket), in a register
        total += start[r, b]
        start[r, b] = total
    start[r, buckets] = count
    for i in range(count - 1, -1, -1):  # backwards: each bucket ends up in ascending order
        b = keys[r, i]
        start[r, b] -= 1
        items[r, start[r, b]] = i
        keys[r, i] = start[r, b]


@inlined
def _row_runs(low_x: int, high_x: int, bits: int) -> tuple[int, int, int]:
    """How a row's buckets of cells ``low_x .. high_x`` lie in the table: ``(runs, first, last)``.

    Unless the cells wrap around the fold, their buckets are side by side
    (columns ``first .. last``), so their points are one run of slots (one
    loop instead of three: fewer mispredicted branches); else one run per bucket.
    """
    fold = (1 << bits) - 1
    first = low_x & fold
    last = high_x & fold
    runs = 1 if first <= last else high_x - low_x + 1
    return runs, first, last


@inlined
def _run_slots(
    r: int,
    row: int,
    run: int,
    runs: int,
    low_x: int,
    first: int,
    last: int,
    bits: int,
    start: np.ndarray,
) -> tuple[int, int]:
    """Slots of run ``run`` of ``_row_runs`` in the row of buckets starting at bucket ``row``."""
    if runs == 1:
        return start[r, row | first], start[r, (row | last) + 1]
    b = row | ((low_x + run) & ((1 << bits) - 1))
    return start[r, b], start[r, b + 1]


@inlined
def near(
    r: int,
    x: float,
    y: float,
    reach: float,
    cell: float,
    bits: int,
    start: np.ndarray,
    items: np.ndarray,
    out: np.ndarray,
    ordered: bool,
) -> int:
    """Points of run ``r`` in the buckets of the cells within ``reach <= cell`` of ``(x, y)``.

    Writes them to ``out[r]`` and returns how many: ascending when
    ``ordered`` (sums over bodies), else in bucket order, row by row (tests
    whose answer does not depend on the order).
    """
    found = 0
    inverse = 1.0 / cell  # as in ``fill``: the same cells
    low_x = math.floor((x - reach) * inverse)
    runs, first, last = _row_runs(low_x, math.floor((x + reach) * inverse), bits)
    for gy in range(math.floor((y - reach) * inverse), math.floor((y + reach) * inverse) + 1):
        row = (gy & ((1 << bits) - 1)) << bits
        for run in range(runs):
            begin, end = _run_slots(r, row, run, runs, low_x, first, last, bits, start)
            for slot in range(begin, end):
                item = items[r, slot]
                position = found
                if ordered:  # insertion sort: the lists are short
                    while position > 0 and out[r, position - 1] > item:
                        out[r, position] = out[r, position - 1]
                        position -= 1
                out[r, position] = item
                found += 1
    return found


@inlined
def near_within(
    r: int,
    x: float,
    y: float,
    cell: float,
    bits: int,
    start: np.ndarray,
    items: np.ndarray,
    item_at: np.ndarray,
    out: np.ndarray,
) -> int:
    """``near`` with reach ``cell``, ascending, of the points less than ``cell`` away in x and y.

    ``item_at[r, slot, 0]``, ``item_at[r, slot, 1]`` are where the point
    ``items[r, slot]`` stood when the grid was built (a copy in bucket order): the test
    reads memory in the order of the buckets instead of jumping by point id,
    and the far points of folded cells never reach the sort.
    """
    found = 0
    inverse = 1.0 / cell  # as in ``fill``: the same cells
    low_x = math.floor((x - cell) * inverse)
    runs, first, last = _row_runs(low_x, math.floor((x + cell) * inverse), bits)
    for gy in range(math.floor((y - cell) * inverse), math.floor((y + cell) * inverse) + 1):
        row = (gy & ((1 << bits) - 1)) << bits
        for run in range(runs):
            begin, end = _run_slots(r, row, run, runs, low_x, first, last, bits, start)
            for slot in range(begin, end):
                if abs(x - item_at[r, slot, 0]) >= cell or abs(y - item_at[r, slot, 1]) >= cell:
                    continue
                item = items[r, slot]
                position = found
                while position > 0 and out[r, position - 1] > item:  # insertion: short lists
                    out[r, position] = out[r, position - 1]
                    position -= 1
                out[r, position] = item
                found += 1
    return found
