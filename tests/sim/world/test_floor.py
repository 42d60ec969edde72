"""How a warehouse floor acts on bodies (``swarmtag.sim.world.floor``) and in full ticks.

Pure-function tests use ``HALL`` with 1 m cells (exact binary fractions);
kernel tests use the default bodies on 0.75 m cells: step 0.05 m per tick,
robot radius 0.125 m, carrier half side 0.1775 m, release 10 ticks.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from swarmtag.policy import Proximity
from swarmtag.sim import Mode, initial_state, run_batch, simulate, step
from swarmtag.sim.config.floor_map import SHELF, FloorMap, parse_floor_map
from swarmtag.sim.config.scenario import Scenario
from swarmtag.sim.config.warehouse import Warehouse
from swarmtag.sim.world.floor import (
    clear_of_shelves,
    inside_area,
    keep_off_shelves,
    transport_waypoints,
)
from swarmtag.sim.world.predock import free_faces
from swarmtag.tag import TagStatus
from tests.sim.helpers import (
    Script,
    event_rows,
    order_scene,
    run_script,
    start,
    warehouse_params,
)

# row 4 is the first line; shelves at (3, 1) and (1, 2)-(1, 4)
HALL = """\
P.....
.#....
......
..###.
.....0
"""
DISC = (0.0, 0.25)  # (extent, radius) of an empty robot: margin 0.25
LOADED = (0.1875, 0.0)  # a robot carrying a carrier of half side 0.1875: margin 0.1875
EXACT = {"rtol": 0, "atol": 1e-12}


@pytest.fixture(scope="module")
def hall() -> FloorMap:
    return parse_floor_map(HALL, cell=1.0, name="hall")


def _kept(floor, x, y, *, cell, body=DISC):
    extent, radius = body
    row, col = cell
    kept = keep_off_shelves(
        np.array([x]),
        np.array([y]),
        extent=np.array([extent]),
        radius=np.array([radius]),
        row=np.array([row]),
        col=np.array([col]),
        floor=floor,
    )
    return [float(kept[0][0]), float(kept[1][0])]


# --- keep_off_shelves ------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("cell", "proposed", "expected"),
    [
        ((2, 1), (1.5, 2.9), [1.5, 2.75]),  # shelf (3, 1) to the north: y <= 3 - 0.25
        ((2, 1), (1.5, 3.1), [1.5, 2.75]),  # clamped by the cell it started in
        ((3, 0), (0.9, 3.5), [0.75, 3.5]),  # shelf to the east: x <= 1 - 0.25
        ((3, 2), (2.1, 3.5), [2.25, 3.5]),  # shelf to the west: x >= 2 + 0.25
        ((4, 1), (1.5, 4.1), [1.5, 4.25]),  # shelf to the south, wall to the north
        ((4, 1), (1.5, 4.9), [1.5, 4.75]),
        ((0, 0), (0.1, 0.1), [0.25, 0.25]),  # the border is a wall all round
        ((4, 5), (5.9, 4.9), [5.75, 4.75]),
        ((3, 4), (5.1, 3.5), [5.1, 3.5]),  # free neighbours: not moved
    ],
)
def test_shelves_beside_the_start_cell_and_the_border_clamp_x_and_y_at_the_margin(
    hall, cell, proposed, expected
):
    assert _kept(hall, *proposed, cell=cell) == expected


def test_a_loaded_robot_is_kept_off_by_its_carrier_half_side(hall):
    assert _kept(hall, 1.5, 2.9, cell=(2, 1), body=LOADED) == [1.5, 3 - 0.1875]
    assert _kept(hall, 0.1, 4.95, cell=(4, 0), body=LOADED) == [0.1875, 5 - 0.1875]
    assert _kept(hall, 2.1, 3.5, cell=(3, 2), body=LOADED) == [2.1875, 3.5]


def test_a_shelf_corner_with_both_cells_between_free_pushes_the_disc_out_radially(hall):
    # start cell (2, 2): shelf (3, 1) is its north-west diagonal, corner at (2, 3)
    x, y = _kept(hall, 2.05, 2.95, cell=(2, 2))
    np.testing.assert_allclose([x, y], [2 + 0.25 / math.sqrt(2), 3 - 0.25 / math.sqrt(2)], **EXACT)
    assert _kept(hall, 2.3, 2.7, cell=(2, 2)) == [2.3, 2.7]  # 0.42 from the corner: free


def test_a_loaded_robot_leaves_a_shelf_corner_along_the_smaller_overlap(hall):
    # square of half side 0.1875 at (2.06, 2.95): overlaps the corner box by 0.1275 in x
    # and 0.1375 in y, so it is pushed out in x only
    assert _kept(hall, 2.06, 2.95, cell=(2, 2), body=LOADED) == [2.1875, 2.95]


@pytest.mark.parametrize(
    ("cell", "proposed", "expected"),
    [
        ((2, 2), (3.02, 2.2), [3.02, 2.25]),  # crossing the seam of shelves (1, 2) and (1, 3)
        ((2, 2), (2.95, 2.2), [2.95, 2.25]),  # by the corner of (1, 3): its south is a shelf
        ((2, 3), (3.95, 2.1), [3.95, 2.25]),
        ((2, 4), (4.6, 2.1), [4.6, 2.25]),  # the last shelf of the row
    ],
)
def test_sliding_along_a_shelf_row_keeps_the_motion_along_it(hall, cell, proposed, expected):
    assert _kept(hall, *proposed, cell=cell) == expected


def test_a_diagonal_shelf_is_no_corner_when_a_cell_between_is_a_shelf():
    # shelves (2, 2) and (1, 2), one above the other
    floor = parse_floor_map("P.#.\n..#0\n....\n", cell=1.0)
    # from (1, 1) the shelf (2, 2) is diagonal, but (1, 2) between is a shelf: clamped in x only
    assert _kept(floor, 1.95, 2.1, cell=(1, 1)) == [1.75, 2.1]
    # from (0, 1) the shelf (1, 2) is diagonal with (1, 1) and (0, 2) free: a corner at (2, 1)
    x, y = _kept(floor, 1.9, 0.9, cell=(0, 1))
    assert math.hypot(x - 2.0, y - 1.0) == pytest.approx(0.25, abs=1e-12)
    assert x - 1.9 == pytest.approx(y - 0.9, abs=1e-12)  # straight away from the corner
    assert x < 1.9


def test_a_batch_of_bodies_is_kept_off_independently(hall):
    x, y = keep_off_shelves(
        np.array([[1.5, 2.05], [0.1, 3.02]]),
        np.array([[2.9, 2.95], [0.1, 2.2]]),
        extent=np.array([[0.0, 0.0], [0.1875, 0.0]]),
        radius=np.array([[0.25, 0.25], [0.0, 0.25]]),
        row=np.array([[2, 2], [0, 2]]),
        col=np.array([[1, 2], [0, 2]]),
        floor=hall,
    )
    c = 0.25 / math.sqrt(2)
    np.testing.assert_allclose(x, [[1.5, 2 + c], [0.1875, 3.02]], **EXACT)
    np.testing.assert_allclose(y, [[2.75, 3 - c], [0.1875, 2.25]], **EXACT)


# --- clear_of_shelves, inside_area, transport_waypoints --------------------------------------


@pytest.mark.parametrize(
    ("point", "clear"),
    [
        ((2.5, 2.5), True),  # middle of a free cell
        ((1.5, 2.75), True),  # exactly the margin below shelf (3, 1)
        ((1.5, 2.76), False),
        ((1.5, 3.5), False),  # on the shelf
        ((0.25, 4.75), True),  # exactly the margin from two walls
        ((0.24, 4.5), False),
        ((5.9, 0.5), False),  # through the east wall
        ((2.2, 2.8), True),  # 0.283 from the corner of (3, 1)
        ((2.15, 2.85), False),  # 0.212 from it
        ((2.3, 1.9), False),  # inside the bottom row of shelves
    ],
)
def test_clear_of_shelves(hall, point, clear):
    x, y = (np.array([v]) for v in point)
    assert clear_of_shelves(x, y, 0.25, hall).tolist() == [clear]


def test_predock_faces_behind_a_shelf_or_the_wall_are_unusable(tmp_path):
    # a carrier on each pick-up cell; the left one has a shelf to its east
    params = warehouse_params(tmp_path / "m.txt", "P#.P.\n.....\n....0\n")
    slots = params.floor.pickup_slots
    assert slots.tolist() == [[0.375, 1.875], [2.625, 1.875]]
    faces = free_faces(slots[None], np.ones((1, 2), dtype=bool), params)
    # faces east, north, west, south
    assert faces[0].tolist() == [[False, False, False, True], [True, False, True, True]]


AREAS = """\
P...
22..
25..
.5.0
"""


@pytest.fixture(scope="module")
def areas() -> FloorMap:
    return parse_floor_map(AREAS, cell=1.0, name="areas")


@pytest.mark.parametrize(
    ("centre", "half", "area", "inside"),
    [
        ((0.5, 1.5), 0.25, 2, True),  # inside cell (1, 0) of area 2
        ((0.5, 2.0), 0.25, 2, True),  # straddles two cells of area 2
        ((0.5, 2.0), 0.49, 2, True),
        ((1.0, 2.5), 0.25, 2, True),
        ((0.5, 1.5), 0.25, 5, False),  # the area id, not another one
        ((1.0, 1.5), 0.25, 2, False),  # straddles areas 2 and 5
        ((1.0, 1.5), 0.25, 5, False),
        ((1.5, 1.9), 0.25, 5, False),  # straddles areas 5 and 2
        ((1.9, 0.5), 0.25, 5, False),  # straddles area 5 and the floor
        ((1.5, 1.0), 0.25, 5, True),
        ((3.5, 0.5), 0.25, 0, True),
        ((3.5, 0.5), 0.25, 1, False),  # there is no area 1
    ],
)
def test_inside_area_needs_every_corner_in_the_area(areas, centre, half, area, inside):
    x, y = (np.array([v]) for v in centre)
    assert inside_area(x, y, half, np.array([area]), areas).tolist() == [inside]


def test_transport_waypoints_index_the_destinations(areas):
    assert areas.destinations == (0, 2, 5)
    position = np.array([[[3.5, 3.5], [3.5, 3.5], [0.2, 0.7], [0.2, 0.7]]])
    destination = np.array([[0, 2, 1, 2]])  # indices: area 0, area 5, area 2, area 5
    waypoints = transport_waypoints(position, destination, areas)
    # from cell (3, 3): south towards area 0, south-west towards area 5 (two diagonals);
    # from cell (0, 0): north into area 2, east into area 5
    assert waypoints.tolist() == [[[3.5, 2.5], [2.5, 2.5], [0.5, 1.5], [1.5, 0.5]]]
    inside = transport_waypoints(np.array([1.2, 0.3]), np.array(2), areas)
    assert inside.tolist() == [1.5, 0.5]  # in its area: the cell's own centre


# --- full ticks ------------------------------------------------------------------------------

ROW = """\
P.......
........
..###...
.......0
"""
# shelves (1, 2)-(1, 4): x in [1.5, 3.75], y in [0.75, 1.5]; a robot on top stands at y 1.625


def test_a_walker_slides_along_a_shelf_row_across_its_seams(tmp_path):
    params = warehouse_params(tmp_path / "row.txt", ROW, robots=1)
    scene = order_scene(params, [(2.2, 1.625)])  # touching the top of shelf (1, 2)
    after = run_script(params, scene, 4, walk=(1.0, 0.0)).final_state
    assert after.robot_pos[0, 0].tolist() == pytest.approx([2.4, 1.625], abs=1e-12)
    assert (after.contact == 0).all()


def test_a_walker_driving_into_a_shelf_row_keeps_its_motion_along_it(tmp_path):
    params = warehouse_params(tmp_path / "row.txt", ROW, robots=1)
    # walking along its heading, it crosses the seam at x = 2.25 this tick
    scene = order_scene(params, [(2.23, 1.64)], heading=[(0.6, -0.8)])
    one = run_script(params, scene, 1, walk=(0.6, -0.8)).final_state
    assert one.robot_pos[0, 0, 1] == 1.625  # held on the shelves' top
    assert one.robot_pos[0, 0, 0] == pytest.approx(2.23 + 0.03, abs=1e-12)
    assert one.contact[0, 0].tolist() == pytest.approx([0.0, 0.025], abs=1e-12)


CROWD = """\
P.P.P...00
..........
.###.##.#.
..........
P.#.P.#...
..#...#.11
"""


def _shelf_depth(floor: FloorMap, pos, extent, radius):
    """Deepest overlap of each body with any shelf, worked out cell by cell (not by the kernel)."""
    rows, cols = np.nonzero(floor.kind == SHELF)
    centre = np.stack(((cols + 0.5) * floor.cell, (rows + 0.5) * floor.cell), axis=-1)
    reach = extent[..., None, None] + floor.cell / 2
    offset = np.abs(pos[..., None, :] - centre)
    outside = np.maximum(offset - reach, 0.0)
    gap = np.hypot(outside[..., 0], outside[..., 1])
    inner = np.min(reach - offset, axis=-1)
    depth = np.where(gap > 0, radius[..., None] - gap, radius[..., None] + inner)
    return depth.max(axis=-1)


@pytest.mark.parametrize("seed", [4, 11])
def test_robots_in_a_crowded_small_warehouse_never_overlap_a_shelf(tmp_path, seed):
    path = tmp_path / "crowd.txt"
    path.write_text(CROWD, encoding="utf-8")
    warehouse = Warehouse(map=str(path), order_interval=2.0, initial_orders=5, urgency_window=60)
    scenario = Scenario(robots=16, ticks=250, warehouse=warehouse)
    result = simulate(
        scenario, Proximity(), seed=seed, runs=3, record=True, check=True, backend="reference"
    )
    traj = result.trajectories
    loaded = np.isin(traj.robot_mode, [Mode.LIFT, Mode.TRANSPORT, Mode.RELEASE]) & (
        traj.robot_target >= 0
    )
    assert loaded.any(), "no robot carried anything: the test would not cover loaded bodies"
    extent = np.where(loaded, 0.1775, 0.0)
    radius = np.where(loaded, 0.0, 0.125)
    floor = parse_floor_map(CROWD, cell=0.75)
    assert _shelf_depth(floor, traj.robot_pos, extent, radius).max() <= 1e-9
    margin = (extent + radius)[..., None]
    size = np.array([floor.width, floor.height])
    assert (traj.robot_pos >= margin - 1e-9).all()
    assert (traj.robot_pos <= size - margin + 1e-9).all()


BEHIND = """\
P........
.........
..#####..
..#####..
2...5....
"""
# destinations (2, 5): index 0 is area 2 (cell (0, 0)), index 1 area 5 (cell (0, 4))


def _loaded(params, at, destination):
    """A robot at ``at`` holding order 0 (for ``destination``, an index), lifted and driving."""
    scene = order_scene(params, [at], due=[0], carriers=[at], destination=[destination])
    s = start(params, scene).copy()
    s.mode[0, 0] = Mode.TRANSPORT
    s.target[0, 0] = 0
    s.ghost[0, 0] = 0
    s.carried_by[0, 0] = 0
    s.status[0, 0] = TagStatus.PICKED_UP
    s.adv_status[0, :, 0] = TagStatus.PICKED_UP
    s.pickup_time[0, 0] = 0
    return s


def test_a_loaded_robot_drives_around_a_shelf_block_to_its_own_area(tmp_path):
    params = warehouse_params(tmp_path / "behind.txt", BEHIND, robots=1, ticks=400)
    assert params.floor.destinations == (2, 5)
    cell = params.floor.cell
    s = _loaded(params, (4.5 * cell, 3.5 * cell), destination=1)  # above the block
    result = run_batch(s, params, Script(params), ticks=200, check=True, record=True)
    final = result.final_state
    delivered = int(final.delivery_time[0, 0])
    # the route has 9 cells (6.75 m, 135 ticks between centres); it cuts corners and releases
    # as soon as the carrier is wholly in area 5, then lowers it for 10 ticks
    assert 110 <= delivered <= 150
    assert event_rows(result) == [(delivered, "deliver", 0, 0)]
    assert not final.present[0, 0]
    x, y = final.carrier_pos[0, 0]
    half = params.carrier_half
    assert 4 * cell <= x - half < x + half <= 5 * cell  # wholly in area 5: cell (0, 4)
    assert 0 <= y - half < y + half <= cell
    xs, ys = result.trajectories.robot_pos[0, :, 0].T
    beside = (xs < 2 * cell) | (xs > 7 * cell)
    assert beside[(ys > cell) & (ys < 3 * cell)].all()  # passed the block beside it, not over


@pytest.mark.parametrize(("destination", "mode"), [(0, Mode.RELEASE), (1, Mode.TRANSPORT)])
def test_a_carrier_is_lowered_only_in_its_own_area(tmp_path, destination, mode):
    params = warehouse_params(tmp_path / "behind.txt", BEHIND, robots=1)
    cell = params.floor.cell
    s = _loaded(params, (0.5 * cell, 0.5 * cell), destination)  # the middle of area 2
    after, _ = step(s, Script(params).inputs(1), params)
    assert after.mode[0, 0] == mode
    if destination == 1:  # drives on towards area 5 (east along row 0)
        assert after.robot_pos[0, 0].tolist() == pytest.approx([0.5 * cell + 0.05, 0.5 * cell])


def test_only_the_orders_due_at_the_start_stand_on_the_floor_at_first(tmp_path):
    params = warehouse_params(tmp_path / "row.txt", ROW, robots=2)
    scene = order_scene(params, [(0.4, 0.4), (1.2, 0.4)], due=[0, 5])
    state = initial_state(params, [scene], [0])
    assert state.present[0].tolist() == [True] + [False] * (params.carriers - 1)
    assert state.arrival_time[0, :2].tolist() == [0, -1]
    assert state.due[0, :2].tolist() == [0, 5]
