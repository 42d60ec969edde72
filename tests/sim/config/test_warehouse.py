"""The ``[warehouse]`` scenario part (``swarmtag.sim.config.warehouse``) and what a warehouse run gives.

Run tests use ``FLOOR`` (0.75 m cells, 4.5 m x 2.25 m): four pick-up slots,
a shelf in the middle and drop-off areas 0 and 1 on the right; times are
in seconds (0.1 s ticks).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from PIL import Image

from swarmtag.errors import ConfigError
from swarmtag.io import format_csv
from swarmtag.policy import Proximity
from swarmtag.sim import Scenario, simulate
from swarmtag.sim.config.warehouse import Warehouse
from swarmtag.sim.determinism import run_csv
from swarmtag.sim.outputs.render import snapshot
from swarmtag.sim.outputs.trajectories import Trajectories

FLOOR = "P.P..0\n..#...\nP.P..1\n"


@pytest.fixture(scope="module")
def map_file(tmp_path_factory):
    path = tmp_path_factory.mktemp("warehouse") / "floor.txt"
    path.write_text(FLOOR, encoding="utf-8")
    return str(path)


# --- the scenario part -----------------------------------------------------------------------


def test_a_warehouse_table_gives_the_part_and_the_carriers_it_preallocates():
    s = Scenario.from_mapping(
        {"robots": 6, "carriers": 3, "ticks": 3000, "warehouse": {"order_interval": 60.0}}
    )
    assert s.warehouse == Warehouse(map="small-warehouse", order_interval=60.0)
    # 300 s at one order a minute: mean 5, plus 6 sqrt(5) + 6, plus the 4 initial orders
    assert s.carriers == 4 + math.ceil(5 + 6 * math.sqrt(5) + 6) == 29
    assert s.carriers == s.warehouse.order_capacity(300.0)


def test_a_warehouse_scenario_round_trips_through_its_mapping_and_toml(tmp_path, map_file):
    path = tmp_path / "hall.toml"
    path.write_text(
        f"""
robots = 5
ticks = 1200

[warehouse]
map = '{map_file}'
cell = 0.8
order_interval = 12.5
initial_orders = 3
urgency_window = 300.0
warmup = 30.0
""",
        encoding="utf-8",
    )
    s = Scenario.from_toml(path)
    assert s.warehouse == Warehouse(
        map=map_file,
        cell=0.8,
        order_interval=12.5,
        initial_orders=3,
        urgency_window=300.0,
        warmup=30.0,
    )
    mapping = s.to_mapping()
    assert mapping["warehouse"] == {
        "map": map_file,
        "cell": 0.8,
        "order_interval": 12.5,
        "initial_orders": 3,
        "urgency_window": 300.0,
        "warmup": 30.0,
    }
    assert Scenario.from_mapping(mapping) == s
    assert Scenario.from_toml(path, {"warehouse.warmup": 0.0}).warehouse.warmup == 0.0


@pytest.mark.parametrize("lab", [Scenario(), Scenario.default(6, 7, profile="lab")])
def test_lab_scenarios_have_no_warehouse_key(lab):
    assert lab.warehouse is None
    assert "warehouse" not in lab.to_mapping()
    assert Scenario.from_mapping(lab.to_mapping()).warehouse is None


@pytest.mark.parametrize(
    ("data", "words"),
    [
        (
            {"urgency": {"model": "static"}},
            "urgency.model: 'static'; a warehouse's orders use the growing model",
        ),
        ({"robots": 14}, "robots: 14 do not fit on the floor of warehouse.map"),
        ({"warehouse": {"cell": 0.5}}, "warehouse.cell: 0.5 m is less than a carrier plus"),
        (
            {"arena": {"carrier_spacing": 0.05}, "warehouse": {"cell": 0.42}},
            "warehouse.cell: 0.42 m is too small for a loaded robot",
        ),
        (
            {"warehouse": {"initial_orders": 5}},
            "warehouse.initial_orders: 5 is more than the map's 4 pick-up cells",
        ),
        ({"warehouse": {"maps": "x"}}, "warehouse.maps: unknown key; [warehouse] has keys"),
        (
            {"reprioritisations": [{"tick": 10, "carrier": 0, "urgency": 9}]},
            "reprioritisations: not available in a warehouse",
        ),
        ({"warehouse": {"order_interval": 0.0}}, "warehouse.order_interval: 0.0 is not a number"),
        (
            {"ticks": 100_000, "warehouse": {"order_interval": 0.01}},
            "at most 100000 per run",
        ),
    ],
)
def test_warehouse_scenarios_that_cannot_run_are_refused(map_file, data, words):
    part = {"map": map_file, **data.pop("warehouse", {})}
    with pytest.raises(ConfigError) as caught:
        Scenario.from_mapping({**data, "warehouse": part})
    assert words in str(caught.value)


def test_thirteen_robots_fit_the_thirteen_start_cells(map_file):
    # 18 cells less 4 pick-up cells and a shelf
    assert Scenario.from_mapping({"robots": 13, "warehouse": {"map": map_file}}).robots == 13


# --- a run's logs ----------------------------------------------------------------------------


def _scenario(map_file):
    warehouse = Warehouse(map=map_file, order_interval=5.0, initial_orders=2, urgency_window=60)
    return Scenario(robots=4, ticks=400, time_unit="s", warehouse=warehouse)


@pytest.fixture(scope="module")
def batch(map_file):
    return simulate(
        _scenario(map_file), Proximity(), seed=3, runs=2, record=True, backend="reference"
    )


def test_the_carrier_log_lists_the_orders_due_by_the_end_of_the_run(batch):
    final, log = batch.final_state, batch.carriers
    assert final.ended_at.tolist() == [400, 400]
    for run in range(2):
        rows = log.take(log.run == run)
        in_run = np.flatnonzero(final.due[run] <= 400)
        assert in_run.size < final.due.shape[1]  # some orders were allocated but never due
        assert rows.carrier.tolist() == in_run.tolist()
        assert rows.order_time.tolist() == (final.due[run, in_run] * 0.1).tolist()
        assert (rows.run_end == 40.0).all()
        delivered = np.isfinite(rows.delivery_time)
        assert delivered.sum() == batch.delivered[run] > 0
        assert rows.delivery_time[delivered].tolist() == pytest.approx(
            (final.delivery_time[run, in_run][delivered] * 0.1).tolist(), abs=1e-12
        )
    orders = (final.due <= 400).sum(axis=1)
    assert batch.undelivered.tolist() == (orders - batch.delivered).tolist()


def test_a_run_gives_the_same_bytes_alone_and_in_a_batch(batch, map_file):
    scenario = _scenario(map_file)
    for run in (0, 1):
        alone = simulate(scenario, Proximity(), seed=3, runs=1, run_offset=run, backend="reference")
        assert run_csv(alone, run) == run_csv(batch, run)
    assert run_csv(batch, 0) != run_csv(batch, 1)
    again = simulate(scenario, Proximity(), seed=3, runs=2, backend="reference")
    assert format_csv(again.carriers) == format_csv(batch.carriers)
    assert format_csv(again.events) == format_csv(batch.events)


# --- drawing and trajectories ----------------------------------------------------------------


def _pixels(image, colour):
    return int((np.asarray(image.convert("RGB")) == colour).all(axis=-1).sum())


def test_a_warehouse_snapshot_draws_the_floor(batch, tmp_path):
    path = tmp_path / "floor.png"
    assert snapshot(batch.trajectories, path, run=1, tick=200) == 200
    with Image.open(path) as image:
        assert image.format == "PNG"
        # 4.5 m x 2.25 m: a wide figure, 8 in by 0.2 + 4 in at 110 dpi
        assert image.size == (880, 462)
        assert _pixels(image, (140, 140, 140)) > 1000  # the shelf, grey 0.55
        assert _pixels(image, (219, 233, 246)) > 1000  # pick-up cells
        assert _pixels(image, (223, 240, 216)) > 1000  # drop-off cells


def test_trajectories_keep_the_floor_through_save_and_load(batch, tmp_path):
    traj = batch.trajectories
    geometry = traj.geometry
    assert geometry.floor_text == FLOOR
    assert (geometry.floor_cell, geometry.arena, geometry.height) == (0.75, 4.5, 2.25)
    assert geometry.extent_y == 2.25
    path = tmp_path / "traj.npz"
    traj.save(path)
    loaded = Trajectories.load(path)
    assert loaded.geometry == geometry
    np.testing.assert_array_equal(loaded.robot_pos, traj.robot_pos)
    np.testing.assert_array_equal(loaded.carrier_present, traj.carrier_present)


def test_a_warehouse_with_more_orders_than_marker_ids_round_trips():
    from swarmtag.sim import load_profile

    part = {"map": "warehouse-hall", "order_interval": 10.0}
    hall = load_profile("lab").scenario({"robots": 36, "ticks": 36000, "warehouse": part})
    assert hall.carriers > 256  # its orders, not marker ids
    assert Scenario.from_mapping(hall.to_mapping()) == hall
    with pytest.raises(ConfigError, match="carriers"):
        Scenario(carriers=257)  # the lab arena's carriers are marker ids
