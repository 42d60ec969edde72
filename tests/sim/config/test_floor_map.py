"""Warehouse floor maps: parsing, refusals, routes to drop-off areas, the shipped maps."""

from __future__ import annotations

import heapq
import math
import time
from importlib import resources

import numpy as np
import pytest

from swarmtag.errors import ConfigError
from swarmtag.sim.config import floor_map, routes
from swarmtag.sim.config.floor_map import (
    DROPOFF,
    FLOOR,
    MAX_MAP_BYTES,
    PICKUP,
    SHELF,
    SHIPPED_MAPS,
    FloorMap,
    load_floor_map,
    parse_floor_map,
)
from swarmtag.sim.config.warehouse import Warehouse, floor_of

TINY = """\
; a tiny hall
..#.1
P.#..
..#..
P....
....0
"""


def parse(text: str, cell: float = 1.0) -> FloorMap:
    return parse_floor_map(text, cell=cell, name="test")


def reference_distances(m: FloorMap, destination: int) -> dict[tuple[int, int], float]:
    """Shortest-path lengths (in cells) to the area, by a plain Dijkstra over the map's cells."""
    free = {(r, c) for r in range(m.rows) for c in range(m.cols) if m.kind[r, c] != SHELF}
    dist = {cell: 0.0 for cell in free if m.area[cell] == destination}
    queue = [(0.0, cell) for cell in sorted(dist)]
    while queue:
        d, (r, c) = heapq.heappop(queue)
        if d > dist[r, c]:
            continue
        for dr in (-1, 0, 1):
            for dc in (-1, 0, 1):
                step = (r + dr, c + dc)
                if step == (r, c) or step not in free:
                    continue
                if dr and dc and ((r + dr, c) not in free or (r, c + dc) not in free):
                    continue  # no corner cutting
                nd = d + (math.sqrt(2) if dr and dc else 1.0)
                if nd < dist.get(step, math.inf) - 1e-12:
                    dist[step] = nd
                    heapq.heappush(queue, (nd, step))
    return dist


# -- parsing ----------------------------------------------------------------------------------


def test_each_character_gives_its_kind_and_row_zero_is_the_last_line():
    m = parse(TINY, cell=0.5)
    assert (m.rows, m.cols, m.width, m.height) == (5, 5, 2.5, 2.5)
    assert m.kind[0].tolist() == [FLOOR] * 4 + [DROPOFF]  # "....0", the last line
    assert m.kind[4].tolist() == [FLOOR, FLOOR, SHELF, FLOOR, DROPOFF]  # "..#.1", the first
    assert m.kind[3, 0] == PICKUP
    assert m.kind.dtype == np.int8
    assert m.area.dtype == np.int64
    assert m.area[0, 4] == 0
    assert m.area[4, 4] == 1
    assert (m.area >= 0).sum() == 2
    assert m.destinations == (0, 1)
    assert m.name == "test"
    assert m.cell == 0.5


def test_pickup_slots_are_cell_centres_row_zero_first():
    m = parse(TINY, cell=0.5)
    assert m.pickup_slots.tolist() == [[0.25, 0.75], [0.25, 1.75]]


def test_blocked_is_the_shelves_inside_a_wall_all_round():
    m = parse(TINY)
    assert m.blocked.shape == (7, 7)
    assert m.blocked[0].all()
    assert m.blocked[-1].all()
    assert m.blocked[:, 0].all()
    assert m.blocked[:, -1].all()
    assert (m.blocked[1:-1, 1:-1] == (m.kind == SHELF)).all()


def test_comments_blank_lines_and_trailing_whitespace_are_dropped():
    text = "\n\n; header\n  ; indented comment\r\n.P.  \r\n; between\n..0\t\n\n\n"
    m = parse(text)
    assert m.kind.tolist() == [[FLOOR, FLOOR, DROPOFF], [FLOOR, PICKUP, FLOOR]]
    assert m.text == ".P.\n..0\n"
    assert parse(m.text).kind.tolist() == m.kind.tolist()


def test_arrays_are_read_only():
    m = parse(TINY)
    for array in (m.kind, m.area, m.pickup_slots, m.waypoint, m.blocked):
        assert not array.flags.writeable


def test_destination_areas_need_not_be_contiguous():
    m = parse("1..1\nP...\n..0.")
    assert m.destinations == (0, 1)
    assert (m.area == 1).sum() == 2
    # from either end of the middle line, the nearest piece of area 1 is straight up
    assert m.waypoint[1, 1, 0].tolist() == [0.5, 2.5]
    assert m.waypoint[1, 1, 3].tolist() == [3.5, 2.5]


# -- refusals ---------------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("text", "message"),
    [
        (
            "P..\n..\n..0",
            "test: line 2 has 2 cells but line 1 has 3; all map lines must have the same length",
        ),
        ("; c\nP..\n\n..0", "test: line 3 has 0 cells but line 2 has 3"),
        (
            "P..\n.x.\n..0",
            "test: line 2, column 2: 'x' is not a map character (# shelf, . floor, P pick-up, 0-9 drop-off)",
        ),
        ("; c\nP..\n..0\n...\n .0", "test: line 5, column 1: ' ' is not a map character"),
        ("P.é\n..0", "test: line 1, column 3: 'é' is not a map character"),
        ("P.p\n..0", "test: line 1, column 3: 'p' is not a map character"),
        ("...\n..0", "test: the map has no pick-up cell (P); at least one is needed"),
        ("P..\n...", "test: the map has no drop-off cell (0-9); at least one is needed"),
        ("\n; only a comment\n\n", "test: the map has no lines (only blank lines and ; comments)"),
        ("", "test: the map has no lines"),
        (
            "PP.\n..0",
            "test: pick-up cells at line 1, column 1 and line 1, column 2 touch; no two P cells may be adjacent, diagonals included, so that carriers (up to one cell wide) leave a gap for robots",
        ),
        (".P.\n..P\n0..", "test: pick-up cells at line 1, column 2 and line 2, column 3 touch"),
        (
            "P.#.\n..#1\n0.#.",
            "test: line 1, column 4: this cell cannot reach drop-off area 0 (shelves wall it off); every non-shelf cell must reach every drop-off area",
        ),
        ("P.#.\n.#..\n#..0", "test: line 1, column 1: this cell cannot reach drop-off area 0"),
        (
            "P..#.\n...#0\n0..#.",
            "test: line 1, column 5: this cell is cut off from the floor at line 1, column 1 by shelves; all non-shelf cells must form one connected floor",
        ),
    ],
)
def test_bad_maps_are_refused_naming_what_and_where(text, message):
    with pytest.raises(ConfigError) as caught:
        parse(text)
    assert str(caught.value).startswith(message)


def test_pickup_cells_one_cell_apart_are_accepted():
    m = parse("P.P\n...\nP.P\n..0")
    assert len(m.pickup_slots) == 4


def test_diagonal_through_a_shelf_corner_does_not_connect_cells():
    # the only link between the halves is a diagonal between two shelves: refused
    with pytest.raises(
        ConfigError, match="line 1, column 1: this cell cannot reach drop-off area 0"
    ):
        parse("P#.\n#.0")


@pytest.mark.parametrize("cell", [0, -1.0, math.nan, math.inf, True, "1"])
def test_cell_must_be_a_positive_finite_number(cell):
    with pytest.raises(ConfigError, match=r"^cell: .* is not a number in \(0, 100000\]$"):
        parse_floor_map("P.0", cell=cell)


def test_oversized_maps_are_refused_before_any_work():
    with pytest.raises(ConfigError, match=r"has 1 lines of 4097 cells; at most 4096 lines"):
        parse("P" + "." * 4095 + "0")
    with pytest.raises(ConfigError, match=r"has 4097 lines of 1 cells"):
        parse("P\n" + ".\n" * 4095 + "0")


# -- routes -----------------------------------------------------------------------------------


ROUTES = """\
..........
.P.####...
...#..#.1.
.P.#..#...
...#.##...
.P......#.
##..#.....
0...#..0..
"""


@pytest.mark.parametrize("text", [ROUTES, TINY], ids=["routes", "tiny"])
def test_each_waypoint_is_a_neighbour_on_a_shortest_path(text):
    m = parse(text, cell=0.5)
    for d, destination in enumerate(m.destinations):
        dist = reference_distances(m, destination)
        for (r, c), here in dist.items():
            x, y = m.waypoint[d, r, c]
            nr, nc = m.cell_of(x, y)
            assert (x, y) == ((nc + 0.5) * 0.5, (nr + 0.5) * 0.5)  # a cell centre
            if here == 0.0:
                assert (nr, nc) == (r, c)
                continue
            dr, dc = int(nr) - r, int(nc) - c
            assert max(abs(dr), abs(dc)) == 1
            step = math.sqrt(2) if dr and dc else 1.0
            assert dist[int(nr), int(nc)] < here
            assert dist[int(nr), int(nc)] + step == pytest.approx(here)
        assert len(dist) == (m.kind != SHELF).sum()  # every free cell was reached


def test_routes_do_not_cut_shelf_corners():
    # from (2, 1) the diagonal step to the drop-off cell (1, 2) would graze the shelf at
    # (2, 2): the route goes down to (1, 1) first
    m = parse("P.#\n..0\n...")
    assert m.waypoint[0, 2, 1].tolist() == [1.5, 1.5]
    # from the P cell (1, 0) the diagonal to (0, 1) would graze the shelf at (0, 0): east first
    corner = parse("P.\n#0")
    assert corner.waypoint[0, 1, 0].tolist() == [1.5, 1.5]
    # where the 2 x 2 block is free the diagonal is taken
    assert parse("P.\n.0").waypoint[0, 1, 0].tolist() == [1.5, 0.5]


def test_area_cells_give_their_own_centre_and_shelves_nan():
    m = parse(ROUTES, cell=2.0)
    for d, destination in enumerate(m.destinations):
        rows, cols = np.nonzero(m.area == destination)
        assert (m.waypoint[d, rows, cols, 0] == (cols + 0.5) * 2.0).all()
        assert (m.waypoint[d, rows, cols, 1] == (rows + 0.5) * 2.0).all()
    shelves = m.kind == SHELF
    assert np.isnan(m.waypoint[:, shelves]).all()
    assert not np.isnan(m.waypoint[:, ~shelves]).any()
    assert m.waypoint.shape == (2, m.rows, m.cols, 2)
    assert m.waypoint.dtype == np.float64


def test_parsing_is_deterministic():
    first, second = parse(ROUTES), parse(ROUTES)
    assert np.array_equal(first.waypoint, second.waypoint, equal_nan=True)


# -- cell_of ----------------------------------------------------------------------------------


def test_cell_of_floors_and_clips_into_the_map():
    m = parse(TINY, cell=0.5)  # 5 x 5 cells, 2.5 m square
    rows, cols = m.cell_of(np.array([0.0, 0.49, 0.5, 2.49, 2.5, -1.0, 99.0]), np.full(7, 1.2))
    assert cols.tolist() == [0, 0, 1, 4, 4, 0, 4]
    assert rows.tolist() == [2] * 7
    assert rows.dtype == np.int64
    assert cols.dtype == np.int64
    row, col = m.cell_of(1.0, -0.1)
    assert (int(row), int(col)) == (0, 2)
    row, col = m.cell_of(math.nan, math.inf)
    assert (int(row), int(col)) == (4, 0)  # y = inf: the top row; x = NaN: column 0
    grid_rows, _ = m.cell_of(np.zeros((2, 3)), np.full((2, 3), 3.0))
    assert grid_rows.shape == (2, 3)
    assert (grid_rows == 4).all()


# -- shipped maps and files -------------------------------------------------------------------


def test_the_maps_folder_and_the_registry_agree():
    folder = resources.files("swarmtag.sim.config") / "presets" / "maps"
    shipped = sorted(
        p.name.removesuffix(".txt") for p in folder.iterdir() if p.name.endswith(".txt")
    )
    assert shipped == sorted(SHIPPED_MAPS)


@pytest.mark.parametrize(
    ("name", "size", "destinations"),
    [("small-warehouse", (10, 16), (0, 1)), ("warehouse-hall", (32, 48), (0, 1, 2, 3))],
)
def test_shipped_maps_load(name, size, destinations):
    m = load_floor_map(name, cell=0.75)
    assert m.name == name
    assert (m.rows, m.cols) == size
    assert m.destinations == destinations
    assert len(m.pickup_slots) >= 6
    assert (m.kind == SHELF).any()
    if name == "warehouse-hall":
        assert (m.width, m.height) == (36.0, 24.0)


def test_a_map_file_loads_by_path(tmp_path):
    path = tmp_path / "mine.txt"
    path.write_text(TINY, encoding="utf-8")
    m = load_floor_map(str(path), cell=1.0)
    assert m.name == str(path)
    assert m.text == parse(TINY).text


def test_errors_in_a_map_file_name_the_file_and_its_line(tmp_path):
    path = tmp_path / "bad.txt"
    path.write_text("; header\nP.\n.?\n", encoding="utf-8")
    with pytest.raises(ConfigError, match=r"bad\.txt: line 3, column 2: '\?' is not a map"):
        load_floor_map(str(path), cell=1.0)


def test_unreadable_sources_are_refused_naming_them(tmp_path):
    with pytest.raises(
        ConfigError, match=r"no such shipped map or file \(shipped maps: small-warehouse"
    ):
        load_floor_map("no-such-map", cell=1.0)
    with pytest.raises(ConfigError, match=r"is a folder"):
        load_floor_map(str(tmp_path), cell=1.0)
    binary = tmp_path / "binary.txt"
    binary.write_bytes(b"\xff\xfe\x00")
    with pytest.raises(ConfigError, match=r"binary\.txt: the floor map file is not UTF-8 text"):
        load_floor_map(str(binary), cell=1.0)


# -- map files: size checked before reading, read once, routes searched where Ctrl-C works -----


@pytest.mark.parametrize("size", [MAX_MAP_BYTES + 1, 3 * 2**30], ids=["just-over", "3GiB"])
def test_a_map_file_over_the_size_limit_is_refused_without_being_read(tmp_path, size):
    path = tmp_path / "huge.txt"
    with path.open("wb") as stream:
        stream.truncate(size)  # sparse: nothing to read but zeros, and no disk used
    begin = time.monotonic()
    with pytest.raises(ConfigError) as refused:
        load_floor_map(str(path), cell=1.0)
    assert time.monotonic() - begin < 0.5
    assert str(refused.value).startswith(f"{path}: the floor map file is ")
    assert str(refused.value).endswith(
        "; at most 32.0 MiB is read (4096 lines of 4096 cells, with room for comments)"
    )


def test_a_map_file_is_parsed_once_while_it_stays_the_same(tmp_path, monkeypatch):
    path = tmp_path / "mine.txt"
    path.write_text(TINY, encoding="utf-8")
    parses = []
    real = floor_map.parse_floor_map
    monkeypatch.setattr(
        floor_map, "parse_floor_map", lambda *a, **k: parses.append(1) or real(*a, **k)
    )
    first = floor_of(Warehouse(map=str(path), cell=1.0))
    assert floor_of(Warehouse(map=str(path), cell=1.0)) is first
    assert load_floor_map(str(path), cell=1.0) is first
    assert len(parses) == 1
    assert load_floor_map(str(path), cell=2.0) is not first  # another cell: another floor
    path.write_text(TINY.replace("P....", "....."), encoding="utf-8")  # changed: read again
    changed = load_floor_map(str(path), cell=1.0)
    assert changed.pickup_slots.shape[0] == first.pickup_slots.shape[0] - 1
    assert len(parses) == 3


def test_a_large_floor_is_searched_in_a_worker_with_the_same_routes(monkeypatch):
    text = ROUTES.replace("0", ".", 1)
    here = parse(text)
    monkeypatch.setattr(routes, "IN_PROCESS_CELLS", 10)  # every map is "large"
    spawned = []
    real = routes.ProcessPoolExecutor
    monkeypatch.setattr(
        routes, "ProcessPoolExecutor", lambda *a, **k: spawned.append(1) or real(*a, **k)
    )
    there = parse(text)
    assert spawned == [1]
    assert np.array_equal(here.waypoint, there.waypoint, equal_nan=True)
    with pytest.raises(
        ConfigError, match=r"line 1, column 4: this cell cannot reach drop-off area 0"
    ):
        parse("P.#.\n..#1\n0.#.")
    with pytest.raises(ConfigError, match=r"line 1, column 5: this cell is cut off from the floor"):
        parse("P..#.\n...#0\n0..#.")
