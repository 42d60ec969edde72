"""Warehouse floors from small ASCII maps: cell kinds, carrier slots and routes to drop-off areas.

A map is text, one character per square cell of side ``cell`` metres;
north is up, so the last map line is the row at y = 0 (``kind[0]``)::

    ; a comment (a line whose first non-blank character is ";")
    ..........11
    .P.P.####...
    ..........00

- ``#`` shelf: a static obstacle robots collide with;
- ``.`` floor;
- ``P`` pick-up cell: floor where orders arrive on carriers, one carrier
  slot at the cell's centre. No two ``P`` cells may touch, diagonals
  included, so carriers up to one cell wide always leave a gap of at least
  one cell for robots;
- ``0``-``9`` drop-off cell of the area of that destination id (floor).
  There may be several pick-up and drop-off areas; the cells of one
  destination need not be contiguous.

Blank lines before and after the map are ignored and trailing whitespace
is stripped; all map lines must have the same length (at most
``MAX_MAP_SIDE`` lines of ``MAX_MAP_SIDE`` cells). The map's border is the
building's outer wall (implicit; ``#`` around the map is allowed, not
needed). A map needs a pick-up and a drop-off cell, and its non-shelf cells
must form one connected floor from which every drop-off area is reached.

Routes: non-shelf cells are the nodes of an 8-connected graph (steps of 1
and sqrt(2) cells); a diagonal step needs both cells beside it free, so
routes never cut a shelf's corner. ``waypoint[d]`` holds, for every cell,
the centre of the next cell on a shortest route to the nearest cell of
destination ``destinations[d]``; the map is pure data, built once.
"""

from __future__ import annotations

import functools
import os
from dataclasses import dataclass, field
from importlib import resources
from typing import Final

import numpy as np
from numpy.typing import ArrayLike, NDArray

from swarmtag._checks import check_number
from swarmtag._inputs import check_path, regular_file
from swarmtag._interrupt import checkpoint
from swarmtag._resources import check_memory, format_bytes
from swarmtag.errors import ConfigError
from swarmtag.sim.config.parts import MAX_LENGTH
from swarmtag.sim.config.routes import search_routes

__all__ = [
    "DROPOFF",
    "FLOOR",
    "MAX_MAP_BYTES",
    "MAX_MAP_SIDE",
    "PICKUP",
    "SHELF",
    "SHIPPED_MAPS",
    "FloorMap",
    "load_floor_map",
    "parse_floor_map",
]

FLOOR: Final = 0
"""Cell kind of plain floor (``.``)."""
SHELF: Final = 1
"""Cell kind of a shelf (``#``): a static obstacle."""
PICKUP: Final = 2
"""Cell kind of a pick-up cell (``P``): floor with one carrier slot at its centre."""
DROPOFF: Final = 3
"""Cell kind of a drop-off cell (``0``-``9``): floor in the area of that destination."""
SHIPPED_MAPS: Final[tuple[str, ...]] = ("small-warehouse", "warehouse-hall")
"""Maps shipped in ``presets/maps/<name>.txt``."""
MAX_MAP_SIDE: Final = 4096
"""Most map lines and most cells per line (routes for 4096 x 4096 cells take gigabytes)."""
MAX_MAP_BYTES: Final = 32 * 2**20
"""Largest map file read (bytes): a map of ``MAX_MAP_SIDE`` lines of ``MAX_MAP_SIDE`` cells
is 16 MiB; as much again for comments and blank lines."""
_CACHE_SIZE: Final = 4
"""Parsed maps kept per process (a scenario, its study's scales and runs share one)."""
_CACHED_MAPS: dict[tuple[object, ...], FloorMap] = {}
"""Parsed map files by path, cell and file identity; least recently used first."""
_BYTES_PER_CELL: Final = 300
"""Peak bytes per cell of reading a map: the route graph's eight edges and Dijkstra's arrays."""
_BYTES_PER_ROUTE: Final = 40
"""Bytes per cell and destination: the waypoints (16) and the distances and predecessors."""

_COMMENT: Final = ";"
_CHARACTERS: Final = "# shelf, . floor, P pick-up, 0-9 drop-off"
_KINDS: Final = np.full(128, -1, dtype=np.int8)
_KINDS[ord(".")] = FLOOR
_KINDS[ord("#")] = SHELF
_KINDS[ord("P")] = PICKUP
_KINDS[ord("0") : ord("9") + 1] = DROPOFF
_AREAS: Final = np.full(128, -1, dtype=np.int64)
_AREAS[ord("0") : ord("9") + 1] = np.arange(10)
_NEIGHBOURS: Final = tuple((dr, dc) for dr in (1, 0, -1) for dc in (-1, 0, 1) if dr or dc)


@dataclass(frozen=True, eq=False)
class FloorMap:
    """A parsed, validated warehouse floor (build it with ``parse_floor_map``/``load_floor_map``).

    Arrays are indexed ``[row, col]`` with row 0 at y = 0 (the last map
    line) and are read-only. ``area`` holds the destination id of drop-off
    cells and -1 elsewhere; ``pickup_slots`` the (x, y) centres of the
    pick-up cells, row 0 first; ``waypoint[d, row, col]`` the (x, y) point
    to drive to next towards ``destinations[d]`` (the cell's own centre
    inside that area, NaN on shelves); ``blocked`` the shelves plus a
    one-cell wall all round, ``blocked[row + 1, col + 1]`` being cell
    (row, col). ``text`` is the map as read, comments stripped.
    """

    name: str
    cell: float
    kind: NDArray[np.int8] = field(repr=False)
    area: NDArray[np.int64] = field(repr=False)
    destinations: tuple[int, ...]
    pickup_slots: NDArray[np.float64] = field(repr=False)
    waypoint: NDArray[np.float64] = field(repr=False)
    blocked: NDArray[np.bool_] = field(repr=False)
    text: str = field(repr=False)

    @property
    def rows(self) -> int:
        """Cells from south to north (map lines)."""
        return int(self.kind.shape[0])

    @property
    def cols(self) -> int:
        """Cells from west to east (characters per map line)."""
        return int(self.kind.shape[1])

    @property
    def width(self) -> float:
        """Extent along x in metres."""
        return self.cols * self.cell

    @property
    def height(self) -> float:
        """Extent along y in metres."""
        return self.rows * self.cell

    @property
    def start_cells(self) -> NDArray[np.int64]:
        """Flat indices (row by row) of the cells robots may start on: floor and drop-off cells."""
        cells: NDArray[np.int64] = np.flatnonzero((self.kind == FLOOR) | (self.kind == DROPOFF))
        return cells

    def cell_of(self, x: ArrayLike, y: ArrayLike) -> tuple[NDArray[np.int64], NDArray[np.int64]]:
        """The (row, col) of the cells holding points (x, y), clipped into the map.

        Points outside the map give the nearest border cell; a NaN
        coordinate gives row or column 0.

        >>> m = parse_floor_map(chr(10).join(["P..", "..0"]), cell=0.5)
        >>> m.cell_of([0.1, 1.4, 9.0], [0.6, 0.0, -3.0])
        (array([1, 0, 0]), array([0, 2, 2]))
        """
        row = _clipped_index(np.asarray(y, dtype=np.float64) / self.cell, self.rows)
        col = _clipped_index(np.asarray(x, dtype=np.float64) / self.cell, self.cols)
        return row, col


def _clipped_index(scaled: NDArray[np.float64], size: int) -> NDArray[np.int64]:
    index = np.nan_to_num(np.clip(np.floor(scaled), 0, size - 1), nan=0.0)
    return np.asarray(index, dtype=np.int64)


def _read_only(*arrays: NDArray[np.generic]) -> None:
    for array in arrays:
        array.flags.writeable = False


def load_floor_map(source: str, *, cell: float) -> FloorMap:
    """A shipped map by name (``"warehouse-hall"``) or a map file by path, parsed and checked.

    A file larger than ``MAX_MAP_BYTES`` is refused from its size alone, before
    it is read. A file is read and parsed once per process while it stays the
    same file (``_CACHED_MAPS``: its path, cell and ``stat`` identity, size and
    times). Every refusal is a ``ConfigError`` naming the map or file.
    """
    if source in SHIPPED_MAPS:
        return _shipped_map(source, cell)
    what = "floor map file"
    path = check_path(source, what=what, error=ConfigError)
    if not os.path.lexists(path):
        msg = (
            f"floor map {source!r}: no such shipped map or file "
            f"(shipped maps: {', '.join(SHIPPED_MAPS)})"
        )
        raise ConfigError(msg)
    file = regular_file(path, what=what, error=ConfigError)
    try:
        with file.open("rb") as stream:
            status = os.fstat(stream.fileno())
            _check_size(source, status.st_size)
            key: tuple[object, ...] = (source, cell, status.st_dev, status.st_ino)
            key += (status.st_size, status.st_mtime_ns, status.st_ctime_ns)
            if key in _CACHED_MAPS:
                _CACHED_MAPS[key] = _CACHED_MAPS.pop(key)  # most recently used last
                return _CACHED_MAPS[key]
            data = stream.read(MAX_MAP_BYTES + 1)  # no more, even if the file grew meanwhile
        _check_size(source, len(data))
        text = data.decode("utf-8")
    except OSError as problem:
        msg = f"{source}: cannot read the {what} ({problem.strerror})"
        raise ConfigError(msg) from None
    except UnicodeDecodeError:
        msg = f"{source}: the {what} is not UTF-8 text"
        raise ConfigError(msg) from None
    floor = parse_floor_map(text, cell=cell, name=source)
    _CACHED_MAPS[key] = floor
    while len(_CACHED_MAPS) > _CACHE_SIZE:
        del _CACHED_MAPS[next(iter(_CACHED_MAPS))]
    return floor


@functools.lru_cache(maxsize=_CACHE_SIZE)
def _shipped_map(name: str, cell: float) -> FloorMap:
    folder = resources.files("swarmtag.sim.config") / "presets" / "maps"
    text = (folder / f"{name}.txt").read_text(encoding="utf-8")
    return parse_floor_map(text, cell=cell, name=name)


def _check_size(source: str, size: int) -> None:
    if size > MAX_MAP_BYTES:
        msg = (
            f"{source}: the floor map file is {format_bytes(size)}; at most "
            f"{format_bytes(MAX_MAP_BYTES)} is read ({MAX_MAP_SIDE} lines of {MAX_MAP_SIDE} "
            "cells, with room for comments)"
        )
        raise ConfigError(msg)


def parse_floor_map(text: str, *, cell: float, name: str = "<map>") -> FloorMap:
    """The floor described by map ``text`` with square cells of ``cell`` metres.

    Errors are ``ConfigError``s that start with ``name`` and give the line
    (1-based in ``text``) and column of the cell at fault.

    >>> m = parse_floor_map('''
    ... ; tiny
    ... P.#
    ... ..0
    ... ''', cell=1.0, name="tiny")
    >>> (m.rows, m.cols, m.destinations), m.kind[0].tolist(), m.pickup_slots.tolist()
    ((2, 3, (0,)), [0, 0, 3], [[0.5, 1.5]])
    >>> m.waypoint[0, 1, 0].tolist(), m.waypoint[0, 0, 2].tolist()
    ([1.5, 0.5], [2.5, 0.5])
    """
    cell = check_number("cell", cell, low=0.0, low_open=True, high=MAX_LENGTH)
    lines, numbers = _map_lines(text, name)
    kind, area = _classify(lines, numbers, name)
    where = _Where(name, numbers)
    _check_pickups(kind, where, name)
    destinations = tuple(int(d) for d in np.unique(area[area >= 0]))
    if not destinations:
        msg = f"{name}: the map has no drop-off cell (0-9); at least one is needed"
        raise ConfigError(msg)
    check_memory(
        f"{name}: a map of {kind.size} cells with {len(destinations)} destinations",
        kind.size * (_BYTES_PER_CELL + _BYTES_PER_ROUTE * len(destinations)),
        error=ConfigError,
    )
    waypoint = _waypoints(kind, area, destinations, cell, where)
    rows, cols = kind.shape
    centres = (np.stack(np.nonzero(kind == PICKUP)[::-1], axis=1).astype(np.float64) + 0.5) * cell
    blocked = np.ones((rows + 2, cols + 2), dtype=np.bool_)
    blocked[1:-1, 1:-1] = kind == SHELF
    _read_only(kind, area, centres, waypoint, blocked)
    return FloorMap(
        name=name,
        cell=cell,
        kind=kind,
        area=area,
        destinations=destinations,
        pickup_slots=centres,
        waypoint=waypoint,
        blocked=blocked,
        text="".join(f"{line}\n" for line in lines),
    )


def _map_lines(text: str, name: str) -> tuple[list[str], list[int]]:
    """The map lines (top first), trailing whitespace gone, and their 1-based line numbers."""
    kept = [
        (number, line.rstrip())
        for number, line in enumerate(text.split("\n"), start=1)
        if not line.lstrip().startswith(_COMMENT)
    ]
    while kept and not kept[-1][1]:
        kept.pop()
    start = next((i for i, (_, line) in enumerate(kept) if line), len(kept))
    kept = kept[start:]
    if not kept:
        msg = f"{name}: the map has no lines (only blank lines and ; comments)"
        raise ConfigError(msg)
    first, cols = kept[0][0], len(kept[0][1])
    if len(kept) > MAX_MAP_SIDE or cols > MAX_MAP_SIDE:
        msg = (
            f"{name}: the map has {len(kept)} lines of {cols} cells; "
            f"at most {MAX_MAP_SIDE} lines of {MAX_MAP_SIDE} cells are allowed"
        )
        raise ConfigError(msg)
    for number, line in kept:
        if len(line) != cols:
            msg = (
                f"{name}: line {number} has {len(line)} cells but line {first} has {cols}; "
                "all map lines must have the same length"
            )
            raise ConfigError(msg)
    return [line for _, line in kept], [number for number, _ in kept]


def _classify(
    lines: list[str], numbers: list[int], name: str
) -> tuple[NDArray[np.int8], NDArray[np.int64]]:
    """Cell kinds and destination ids, row 0 at the bottom; the first bad character refused."""
    rows, cols = len(lines), len(lines[0])
    codes = np.array(lines, dtype=f"<U{cols}").view(np.uint32).reshape(rows, cols)
    ascii_codes = np.where(codes < 128, codes, 0).astype(np.intp)
    kind = np.where(codes < 128, _KINDS[ascii_codes], -1).astype(np.int8)
    bad = np.flatnonzero(kind < 0)
    if bad.size:
        row, col = divmod(int(bad[0]), cols)
        msg = (
            f"{name}: line {numbers[row]}, column {col + 1}: {lines[row][col]!r} is not a map "
            f"character ({_CHARACTERS})"
        )
        raise ConfigError(msg)
    return np.ascontiguousarray(kind[::-1]), np.ascontiguousarray(_AREAS[ascii_codes][::-1])


@dataclass(frozen=True)
class _Where:
    """Names a cell (row 0 at the bottom) by its line and column in the map text."""

    name: str
    numbers: list[int]

    def __call__(self, row: int, col: int) -> str:
        return f"line {self.numbers[len(self.numbers) - 1 - row]}, column {col + 1}"

    def first(self, mask: NDArray[np.bool_]) -> tuple[int, int]:
        """The (row, col) of the first True cell in text order (top line first)."""
        rows, cols = mask.shape
        text_row, col = divmod(int(np.argmax(mask[::-1].ravel())), cols)
        return rows - 1 - text_row, col


def _check_pickups(kind: NDArray[np.int8], where: _Where, name: str) -> None:
    """At least one pick-up cell, and no two touching (diagonals included)."""
    pickup = kind == PICKUP
    if not pickup.any():
        msg = f"{name}: the map has no pick-up cell (P); at least one is needed"
        raise ConfigError(msg)
    rows, cols = pickup.shape
    padded = np.zeros((rows + 2, cols + 2), dtype=np.bool_)
    padded[1:-1, 1:-1] = pickup
    touching = np.zeros_like(pickup)
    for dr, dc in _NEIGHBOURS:
        touching |= padded[1 + dr : rows + 1 + dr, 1 + dc : cols + 1 + dc]
    touching &= pickup
    if touching.any():
        row, col = where.first(touching)
        other = next(
            (row + dr, col + dc)
            for dr, dc in _NEIGHBOURS
            if 0 <= row + dr < rows and 0 <= col + dc < cols and pickup[row + dr, col + dc]
        )
        msg = (
            f"{name}: pick-up cells at {where(row, col)} and {where(*other)} touch; no two P "
            "cells may be adjacent, diagonals included, so that carriers (up to one cell "
            "wide) leave a gap for robots"
        )
        raise ConfigError(msg)


def _waypoints(
    kind: NDArray[np.int8],
    area: NDArray[np.int64],
    destinations: tuple[int, ...],
    cell: float,
    where: _Where,
) -> NDArray[np.float64]:
    """(D, rows, cols, 2): next cell's centre towards each destination; refuses cut-off cells."""
    name = where.name
    rows, cols = kind.shape
    free = kind != SHELF
    routes, labels = search_routes(
        free, [np.flatnonzero(area == destination) for destination in destinations]
    )
    cells = np.arange(rows * cols)
    centres = np.stack([(cells % cols + 0.5) * cell, (cells // cols + 0.5) * cell], axis=1)
    waypoint = np.full((len(destinations), rows * cols, 2), np.nan, dtype=np.float64)
    for d, (destination, (reached, previous)) in enumerate(zip(destinations, routes, strict=True)):
        checkpoint()
        cut_off = free & ~reached.reshape(rows, cols)
        if cut_off.any():
            row, col = where.first(cut_off)
            msg = (
                f"{name}: {where(row, col)}: this cell cannot reach drop-off area {destination} "
                "(shelves wall it off); every non-shelf cell must reach every drop-off area"
            )
            raise ConfigError(msg)
        following = np.where(previous >= 0, previous, cells)
        waypoint[d, free.ravel()] = centres[following[free.ravel()]]
    _check_connected(labels.reshape(free.shape), free, where)
    return waypoint.reshape(len(destinations), rows, cols, 2)


def _check_connected(labels: NDArray[np.int32], free: NDArray[np.bool_], where: _Where) -> None:
    """All non-shelf cells in one piece, so that robots can get from any cell to any other."""
    start = where.first(free)
    apart = free & (labels != labels[start])
    if apart.any():
        row, col = where.first(apart)
        msg = (
            f"{where.name}: {where(row, col)}: this cell is cut off from the floor at "
            f"{where(*start)} by shelves; all non-shelf cells must form one connected floor"
        )
        raise ConfigError(msg)
