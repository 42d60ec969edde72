"""Shortest routes over a warehouse floor's cells, searched where Ctrl-C can still end them.

The floor's free cells are the nodes of an 8-connected graph (steps of 1
and sqrt(2) cells; a diagonal step needs the whole 2 x 2 block free, so no
route cuts a shelf's corner). ``search_routes`` gives, for each destination,
which cells reach it and each cell's predecessor on a shortest route to its
nearest source cell, and the floor's connected pieces.

scipy's Dijkstra and component search are compiled code that hold the
interpreter for their whole run (8 s for one destination of a 4096 x 4096
map), so no signal handler runs meanwhile and a Ctrl-C would wait for them.
A floor of more than ``IN_PROCESS_CELLS`` cells is therefore searched in a
worker process (``swarmtag._pools``: deaf to SIGINT) while this process waits
for it interruptibly, and a Ctrl-C stops the worker at once. A smaller floor
is searched here: it takes at most about half a second.
"""

from __future__ import annotations

import importlib
import math
from concurrent.futures import ProcessPoolExecutor
from typing import Any, Final

import numpy as np
from numpy.typing import NDArray

from swarmtag._interrupt import checkpoint
from swarmtag._pools import spawn_context, stop

__all__ = ["IN_PROCESS_CELLS", "Routes", "search_routes"]

IN_PROCESS_CELLS: Final = 2**20
"""Largest floor searched in this process (one destination: about 0.5 s on a two-core VM)."""

Routes = tuple[list[tuple[NDArray[np.bool_], NDArray[np.int32]]], NDArray[np.int32]]
"""Per destination (cells that reach it, each cell's predecessor), and each cell's piece."""


def _csgraph() -> Any:  # noqa: ANN401 - scipy ships no type stubs
    """``scipy.sparse.csgraph``, imported on first use (it takes a quarter second to import)."""
    return importlib.import_module("scipy.sparse.csgraph")


def _floor_graph(free: NDArray[np.bool_]) -> Any:  # noqa: ANN401 - a scipy sparse matrix
    """Steps between free cells (flat index row * cols + col): 1 across a side, sqrt(2) diagonally.

    Each step is stored once (east, north, north-east, north-west); the
    graph is meant to be read as undirected. A diagonal step needs the whole
    2 x 2 block free, so no route cuts a shelf's corner.
    """
    rows, cols = free.shape
    index = np.arange(rows * cols, dtype=np.int32).reshape(rows, cols)
    block = free[:-1, :-1] & free[:-1, 1:] & free[1:, :-1] & free[1:, 1:]
    steps = (
        (free[:, :-1] & free[:, 1:], index[:, :-1], index[:, 1:], 1.0),
        (free[:-1, :] & free[1:, :], index[:-1, :], index[1:, :], 1.0),
        (block, index[:-1, :-1], index[1:, 1:], math.sqrt(2.0)),
        (block, index[:-1, 1:], index[1:, :-1], math.sqrt(2.0)),
    )
    tails = np.concatenate([tail[mask] for mask, tail, _, _ in steps])
    heads = np.concatenate([head[mask] for mask, _, head, _ in steps])
    costs = np.concatenate(
        [np.full(int(mask.sum()), cost, dtype=np.float64) for mask, _, _, cost in steps]
    )
    sparse = importlib.import_module("scipy.sparse")
    return sparse.csr_array((costs, (tails, heads)), shape=(rows * cols, rows * cols))


def _search(free: NDArray[np.bool_], sources: list[NDArray[np.int64]]) -> Routes:
    """The search itself (see ``search_routes``), in whichever process runs it."""
    graph = _floor_graph(free)
    routes = []
    for cells in sources:
        checkpoint()
        distance, previous, _ = _csgraph().dijkstra(
            graph, directed=False, indices=cells, min_only=True, return_predecessors=True
        )
        routes.append((np.isfinite(distance), previous.astype(np.int32, copy=False)))
    checkpoint()
    _, labels = _csgraph().connected_components(graph, directed=False)
    return routes, labels.astype(np.int32, copy=False)


def search_routes(free: NDArray[np.bool_], sources: list[NDArray[np.int64]]) -> Routes:
    """Routes on the floor whose free cells are ``free`` to each group of ``sources`` cells.

    For each group (flat cell indices): which cells reach one of them, and each
    cell's predecessor on a shortest route to the nearest (negative at the sources
    and where none is reached); then each cell's connected piece (a label).
    A floor of more than ``IN_PROCESS_CELLS`` cells is searched in a worker process
    (see the module docs).
    """
    if free.size <= IN_PROCESS_CELLS:
        return _search(free, sources)
    pool = ProcessPoolExecutor(max_workers=1, mp_context=spawn_context())
    try:
        result: Routes = pool.submit(_search, free, sources).result()
    except BaseException:
        stop(pool)  # a Ctrl-C (or a failure): the worker goes at once
        raise
    pool.shutdown(wait=True)
    return result
