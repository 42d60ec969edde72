"""Warehouse orders (``swarmtag.sim.world.orders``): sampling a run's orders, placing them as they fall due.

Placement tests use ``SLOTS`` (0.75 m cells): three pick-up slots in the top
row, in slot order at x = 0.375, 1.875, 3.375 (y = 1.875); the urgency
window is 60 s = 600 ticks.
"""

from __future__ import annotations

import math
from dataclasses import fields

import numpy as np
import pytest

from swarmtag.policy import Proximity, Urgency
from swarmtag.sim import Realism, Scenario, TickEvents, make_params, simulate
from swarmtag.sim.config.floor_map import DROPOFF, FLOOR
from swarmtag.sim.config.warehouse import Warehouse
from swarmtag.sim.model.events import EventKind
from swarmtag.sim.model.randomness import Stream, stream, unit_vectors
from swarmtag.sim.model.scene import sample_scene
from swarmtag.sim.model.state import Scene
from swarmtag.sim.world.orders import place_orders
from swarmtag.tag import TagStatus
from tests.sim.helpers import order_scene, start, warehouse_params

SLOTS = """\
P.P.P
.....
....0
"""
SLOT_X = (0.375, 1.875, 3.375)
SLOT_Y = 1.875
FAR = [(1.125, 0.375), (2.625, 0.375)]  # two robots in the bottom row, far from every slot
WINDOW = 600.0


def _expected_urgency(w0: float, t: int, due: int) -> int:
    return min(9, math.floor(9 * (w0 + t - due) / WINDOW))


def _warehouse(tmp_path, **part):
    return warehouse_params(
        tmp_path / "slots.txt",
        SLOTS,
        robots=2,
        realism={"status_delay": 2},
        warehouse={"urgency_window": WINDOW / 10, **part},
    )


def _orders(params, *, due, pick, draw, robots=FAR):
    """A state with the given orders (none placed), their growth base as the sampler stores it."""
    w0 = [d - t for d, t in zip(draw, due, strict=True)]
    scene = order_scene(params, robots, due=due, slot_pick=pick, w0=w0)
    return start(params, scene).copy()


def _place(s, params, t):
    events = TickEvents()
    place_orders(s, params, t=t, events=events)
    return [(e.kind, e.run, e.carrier, e.value) for e in events.carrier_entries]


# --- sampling --------------------------------------------------------------------------------


@pytest.fixture(scope="module")
def shipped():
    scenario = Scenario(
        robots=12,
        ticks=3000,
        realism=Realism(speed_variation=0.1),
        warehouse=Warehouse(initial_orders=8, order_interval=10.0),
    )
    return make_params(scenario, Proximity())


def test_the_scene_draws_follow_the_documented_order(shipped):
    params, floor = shipped, shipped.floor
    scene = sample_scene(params, seed=7, run=3)
    rng = stream(7, 3, Stream.SCENE)
    c, n, initial = params.carriers, params.robots, 8
    first = rng.permutation(floor.pickup_slots.shape[0])[:initial]
    w0 = rng.random(c) * params.horizon
    destination = rng.integers(len(floor.destinations), size=c)
    gaps = rng.exponential(100.0, c - initial)  # 10 s between orders = 100 ticks
    due = np.concatenate((np.zeros(initial), np.floor(np.cumsum(gaps)) + 1)).astype(np.int64)
    slot_pick = rng.random(c)
    cells = np.flatnonzero((floor.kind == FLOOR) | (floor.kind == DROPOFF))
    row, col = np.divmod(cells[rng.permutation(cells.size)[:n]], floor.cols)
    centre = np.stack(((col + 0.5) * 0.75, (row + 0.5) * 0.75), axis=-1)
    robot_pos = centre + (rng.random((n, 2)) - 0.5) * (0.75 - 0.25)
    heading = unit_vectors(rng.standard_normal((n, 2)))
    factor = np.clip(1.0 + 0.1 * rng.standard_normal(n), 0.5, 1.5)
    phase = rng.random(c)

    assert params.horizon == 6000.0  # the urgency window, 600 s, in ticks
    assert scene.slot[:initial].tolist() == first.tolist()
    assert (scene.slot[initial:] == -1).all()
    np.testing.assert_array_equal(scene.due, due)
    np.testing.assert_array_equal(scene.w0, w0 - due)
    np.testing.assert_array_equal(scene.destination, destination)
    np.testing.assert_array_equal(scene.slot_pick, slot_pick)
    np.testing.assert_array_equal(scene.robot_pos, robot_pos)
    np.testing.assert_array_equal(scene.heading, heading)
    np.testing.assert_array_equal(scene.speed_factor, factor)
    np.testing.assert_array_equal(scene.advert_phase, phase)
    np.testing.assert_array_equal(scene.order_time, due)
    urgency0 = np.where(due == 0, np.minimum(9, np.floor(9 * w0 / 6000.0)), 0)
    np.testing.assert_array_equal(scene.urgency0, urgency0)


def _same_scene(a: Scene, b: Scene) -> bool:
    return all(
        np.array_equal(getattr(a, f.name), getattr(b, f.name), equal_nan=True)
        for f in fields(Scene)
    )


def test_sampling_is_a_function_of_seed_and_run_alone(shipped):
    other = make_params(shipped.scenario, Urgency(alpha=3.0))
    scene = sample_scene(shipped, seed=2, run=5)
    assert _same_scene(scene, sample_scene(shipped, seed=2, run=5))
    assert _same_scene(scene, sample_scene(other, seed=2, run=5))
    assert not np.array_equal(scene.due, sample_scene(shipped, seed=2, run=6).due)
    assert not np.array_equal(scene.due, sample_scene(shipped, seed=3, run=5).due)


@pytest.mark.parametrize("run", range(4))
def test_orders_come_in_due_order_and_the_initial_ones_stand_on_distinct_slots(shipped, run):
    floor, c = shipped.floor, shipped.carriers
    scene = sample_scene(shipped, seed=0, run=run)
    assert (scene.due[:8] == 0).all()
    assert (scene.due[8:] >= 1).all()
    assert (np.diff(scene.due) >= 0).all()
    assert sorted(scene.slot[:8].tolist()) == list(range(8))  # all eight slots, once each
    np.testing.assert_array_equal(scene.carrier_pos[:8], floor.pickup_slots[scene.slot[:8]])
    assert scene.destination.min() >= 0
    assert scene.destination.max() < len(floor.destinations)
    state = start(shipped, scene)
    assert state.present[0].tolist() == [True] * 8 + [False] * (c - 8)
    assert state.arrival_time[0].tolist() == [0] * 8 + [-1] * (c - 8)


@pytest.mark.parametrize("run", range(4))
def test_robots_start_one_to_a_floor_cell_and_inside_it(shipped, run):
    floor = shipped.floor
    scene = sample_scene(shipped, seed=1, run=run)
    row, col = floor.cell_of(scene.robot_pos[:, 0], scene.robot_pos[:, 1])
    assert len(set(zip(row.tolist(), col.tolist(), strict=True))) == shipped.robots
    assert np.isin(floor.kind[row, col], [FLOOR, DROPOFF]).all()
    low = np.stack((col, row), axis=-1) * floor.cell + 0.125
    assert (scene.robot_pos >= low).all()
    assert (scene.robot_pos <= low + floor.cell - 0.25).all()


# --- placing ---------------------------------------------------------------------------------


def test_orders_due_take_the_picked_free_slot_in_order_and_the_rest_wait(tmp_path):
    params = _warehouse(tmp_path)
    s = _orders(params, due=[1, 1, 1, 1], pick=[0.9, 0.0, 0.5, 0.99], draw=[0, 120.5, 300.2, 10])
    arrived = _place(s, params, t=1)
    # free [0, 1, 2]: order 0 takes floor(0.9 * 3) = 2; [0, 1]: order 1 takes 0; [1]: order 2
    assert s.slot[0, :4].tolist() == [2, 0, 1, -1]
    assert s.carrier_pos[0, :3].tolist() == [[x, SLOT_Y] for x in (3.375, 0.375, 1.875)]
    assert s.present[0, :4].tolist() == [True, True, True, False]
    assert s.arrival_time[0, :4].tolist() == [1, 1, 1, -1]
    assert s.urgency[0, :3].tolist() == [0, 1, 4]  # floor(9 * 120.5 / 600) = 1, ...
    assert s.urgency0[0, :3].tolist() == [0, 1, 4]
    assert arrived == [(EventKind.ARRIVE, 0, c, float(u)) for c, u in ((0, 0), (1, 1), (2, 4))]


def test_an_order_placed_late_has_the_urgency_of_its_wait_since_it_fell_due(tmp_path):
    params = _warehouse(tmp_path)
    draw = [0, 0, 0, 500.3, 200.0]
    s = _orders(params, due=[1, 1, 1, 1, 3], pick=[0.0, 0.0, 0.0, 0.99, 0.4], draw=draw)
    _place(s, params, t=1)
    assert s.slot[0, :3].tolist() == [0, 1, 2]
    for t in (2, 3, 4):
        assert _place(s, params, t=t) == []  # order 3 waits for a slot, and order 4 behind it
    s.present[0, 1] = False  # the carrier on slot 1 was delivered
    s.delivery_time[0, 1] = 4
    assert _place(s, params, t=5) == [(EventKind.ARRIVE, 0, 3, 7.0)]  # order 3 first (FIFO)
    assert s.slot[0, 3] == 1
    assert s.urgency[0, 3] == _expected_urgency(500.3, 5, 1) == 7
    assert s.arrival_time[0, 4] == -1
    s.present[0, 0] = False
    assert _place(s, params, t=9) == [(EventKind.ARRIVE, 0, 4, 3.0)]
    assert s.slot[0, 4] == 0
    assert s.urgency[0, 4] == _expected_urgency(200.0, 9, 3) == 3


def test_urgency_at_placement_is_capped_at_nine(tmp_path):
    params = _warehouse(tmp_path)
    assert params.horizon == WINDOW
    s = _orders(params, due=[50], pick=[0.0], draw=[599.0])
    _place(s, params, t=150)
    assert s.urgency[0, 0] == 9  # floor(9 * 699 / 600) = 10, capped


def test_a_lifted_carrier_frees_its_slot_a_standing_one_does_not(tmp_path):
    params = _warehouse(tmp_path)
    s = _orders(params, due=[0, 0, 5], pick=[0.0, 0.0, 0.0], draw=[0, 0, 0])
    s.present[0, :2] = True
    s.slot[0, :2] = [0, 2]
    s.arrival_time[0, :2] = 0
    s.carrier_pos[0, :2] = [(0.375, SLOT_Y), (3.375, SLOT_Y)]
    s.carried_by[0, 0] = 0  # carrier 0 is lifted (its robot carries it away) ...
    s.carrier_pos[0, 0] = s.robot_pos[0, 0]
    _place(s, params, t=5)
    assert s.slot[0, 2] == 0  # ... so slot 0 is free again; slot 2 still holds carrier 1


@pytest.mark.parametrize(
    ("robot_x", "slot"),
    [
        (1.875 + 0.30, 2),  # overlaps a carrier on slot 1 (reach 0.1775 + 0.125 = 0.3025)
        (1.875 - 0.30, 2),
        (1.875 + 0.31, 1),  # clear of it
        (1.875, 2),  # right on it
    ],
)
def test_nobody_sets_a_carrier_down_on_a_robot(tmp_path, robot_x, slot):
    params = _warehouse(tmp_path)
    s = _orders(params, due=[0, 2], pick=[0.0, 0.0], draw=[0, 0])
    s.slot[0, 0] = 0  # slot 0 holds carrier 0
    s.robot_pos[0, 1] = (robot_x, SLOT_Y)
    _place(s, params, t=2)
    # free slots [1, 2]: order 1 takes slot 1; with a robot on slot 1, [2]: slot 2
    assert s.slot[0, 1] == slot


def test_a_placed_order_is_advertised_in_every_history_slot_and_gets_its_faces(tmp_path):
    params = _warehouse(tmp_path)
    assert params.status_delay == 2
    s = _orders(params, due=[3, 3], pick=[0.5, 0.0], draw=[400.0, 0])
    s.adv_status[0, :, :2] = -1  # whatever the slots held before
    s.free_face[0, :2] = False
    _place(s, params, t=3)
    assert s.slot[0, :2].tolist() == [1, 0]
    assert s.adv_status[0, :, :2].tolist() == [[TagStatus.AWAITING_PICKUP] * 2] * 3
    assert s.adv_urgency[0, :, :2].tolist() == [[6, 0]] * 3
    # faces east, north, west, south: the north faces lie outside the map, slot 0's west too
    assert s.free_face[0, :2].tolist() == [[True, False, True, True], [True, False, False, True]]


def test_orders_not_yet_due_and_ended_runs_are_left_alone(tmp_path):
    params = _warehouse(tmp_path)
    s = _orders(params, due=[4], pick=[0.0], draw=[0])
    assert _place(s, params, t=3) == []
    s.ended_at[0] = 3
    assert _place(s, params, t=4) == []
    assert not s.present[0].any()
    s.ended_at[0] = -1
    assert [e[2] for e in _place(s, params, t=4)] == [0]


# --- in full runs ----------------------------------------------------------------------------

TINY = "P.P..0\n......\nP.P..1\n"


@pytest.fixture(scope="module")
def run(tmp_path_factory):
    path = tmp_path_factory.mktemp("orders") / "tiny.txt"
    path.write_text(TINY, encoding="utf-8")
    warehouse = Warehouse(map=str(path), order_interval=5.0, initial_orders=2, urgency_window=60)
    scenario = Scenario(robots=4, ticks=500, warehouse=warehouse)
    return simulate(scenario, Proximity(), seed=0, runs=2, check=True, backend="reference")


def test_arrive_rows_name_the_carrier_and_its_urgency_but_no_robot(run):
    final, events = run.final_state, run.events
    arrive = events.take(events.kind == "arrive")
    placed = np.argwhere(final.arrival_time > 0)  # (row, carrier); the initial orders at 0
    assert len(arrive) == len(placed) > 4
    rows = sorted(zip(arrive.run.tolist(), arrive.carrier.tolist(), strict=True))
    assert rows == sorted(map(tuple, placed.tolist()))
    assert (arrive.robot == -1).all()
    r, c = arrive.run, arrive.carrier
    assert arrive.time.tolist() == final.arrival_time[r, c].astype(float).tolist()
    assert arrive.value.tolist() == final.urgency0[r, c].astype(float).tolist()


def test_orders_are_placed_first_come_first_served_with_the_urgency_of_their_wait(run):
    final = run.final_state
    for row in range(2):
        arrival, due = final.arrival_time[row], final.due[row]
        placed = arrival >= 0
        count = int(placed.sum())
        assert placed[:count].all()  # the placed orders are the first ones ...
        assert (np.diff(arrival[:count]) >= 0).all()  # ... in order number
        assert (arrival[placed] >= due[placed]).all()
        waited = (final.w0[row] + arrival)[placed]  # growth base: draw minus due tick
        expected = np.minimum(9, np.floor(9 * waited / WINDOW))
        assert final.urgency0[row, placed].tolist() == expected.tolist()
    assert (final.arrival_time > final.due).any()  # some order had to wait for a slot


def test_unplaced_orders_never_meet_a_robot(run):
    final = run.final_state
    unplaced = final.arrival_time < 0
    assert unplaced.any()
    assert not final.present[unplaced].any()
    assert (final.pickup_time[unplaced] == -1).all()
    assert (final.known_status.transpose(0, 2, 1)[unplaced] == -1).all()  # never heard
    assert (final.seen_tick.transpose(0, 2, 1)[unplaced] == -1).all()  # never seen
    assert (final.urgency[unplaced] == 0).all()  # no urgency grows before the order is placed
    assert final.due[unplaced].min() > 0
