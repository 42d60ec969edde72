"""A recorded run written as MCAP imports back to exactly its event log and event table."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from swarmtag.errors import ConfigError
from swarmtag.io import format_csv
from swarmtag.io.bags import read_bag
from swarmtag.policy import Proximity
from swarmtag.sim import Reprioritisation, simulate
from swarmtag.sim.config.profiles import load_profile
from swarmtag.sim.outputs.mcap import _floor_cells, write_mcap

pytest.importorskip("rosbags")


def scenario(time_unit: str):
    return load_profile("base").scenario(
        {"robots": 2, "carriers": 3, "ticks": 500, "time_unit": time_unit}
    )


@pytest.fixture(scope="module", params=["tick", "s"])
def recorded(request):
    """Runs 4-5 with operator writes on a carrier's lift and delivery ticks and after it.

    Proximity ignores urgency, so the writes do not move the lift and the delivery.
    """
    plain = simulate(scenario(request.param), Proximity(), seed=2, runs=1, run_offset=5)
    log = plain.carriers
    scale = 1.0 if log.time_unit == "tick" else 0.1
    first = int(np.nanargmin(log.delivery_time))
    lift, drop = (
        round(float(t) / scale) for t in (log.pickup_time[first], log.delivery_time[first])
    )
    writes = (
        Reprioritisation(tick=lift, carrier=first, urgency=9),
        Reprioritisation(tick=drop, carrier=first, urgency=0),
        Reprioritisation(tick=drop + 3, carrier=first, urgency=4),
        Reprioritisation(tick=2, carrier=(first + 1) % 3, urgency=8),
    )
    chosen = dataclasses.replace(scenario(request.param), reprioritisations=writes)
    batch = simulate(chosen, Proximity(), seed=2, runs=2, run_offset=4, record=True)
    again = batch.carriers.take(batch.carriers.run == 5)
    assert round(float(again.delivery_time[first]) / scale) == drop
    return batch


def test_the_round_trip_gives_the_identical_event_log_and_table(recorded, tmp_path):
    path = tmp_path / "run.mcap"
    ticks = write_mcap(path, recorded.trajectories, recorded.carriers, recorded.events, run=5)
    logs = read_bag(path, with_events=True)
    log = recorded.carriers.take(recorded.carriers.run == 5)
    table = recorded.events.take(recorded.events.run == 5)
    assert logs.carriers == log
    assert format_csv(logs.carriers) == format_csv(log)
    assert logs.events == table
    assert (table.kind == "reprioritise").sum() == 4
    assert ticks == int(recorded.end_tick[1]) + 1


def test_the_urgency_at_delivery_survives_a_write_in_the_same_tick(recorded, tmp_path):
    write_mcap(
        tmp_path / "run.mcap", recorded.trajectories, recorded.carriers, recorded.events, run=5
    )
    log = read_bag(tmp_path / "run.mcap").carriers
    delivered = int(np.nanargmin(log.delivery_time))
    # the write of the delivery tick comes after the release: the log keeps the urgency before it
    assert (
        log.urgency_end[delivered]
        == recorded.carriers.take(recorded.carriers.run == 5).urgency_end[delivered]
    )
    assert log.urgency_end[delivered] != 0


def test_the_same_run_gives_the_same_bytes(recorded, tmp_path):
    for name in ("a", "b"):
        (tmp_path / name).mkdir()
        write_mcap(
            tmp_path / name / "run.mcap",
            recorded.trajectories,
            recorded.carriers,
            recorded.events,
            run=4,
        )
    assert (tmp_path / "a" / "run.mcap").read_bytes() == (tmp_path / "b" / "run.mcap").read_bytes()


def test_a_run_not_recorded_is_refused(recorded, tmp_path):
    with pytest.raises(ConfigError, match="run: 9 was not recorded"):
        write_mcap(
            tmp_path / "run.mcap", recorded.trajectories, recorded.carriers, recorded.events, run=9
        )
    assert list(tmp_path.iterdir()) == []


def test_a_warehouse_run_round_trips(tmp_path):
    lab = load_profile("lab").scenario({"robots": 6, "ticks": 3000})
    part = {"map": "small-warehouse", "order_interval": 30.0, "initial_orders": 6}
    warehouse = type(lab).from_mapping({**lab.to_mapping(), "warehouse": part})
    result = simulate(warehouse, Proximity(), seed=4, runs=1, record=True)
    assert result.delivered[0] > 0
    assert (result.events.kind == "arrive").sum() > 0
    path = tmp_path / "warehouse.mcap"
    write_mcap(path, result.trajectories, result.carriers, result.events, run=0)
    logs = read_bag(path, with_events=True)
    assert format_csv(logs.carriers) == format_csv(result.carriers)
    assert logs.events == result.events


def test_the_scene_of_a_warehouse_holds_its_shelves_and_areas():
    lab = load_profile("lab").scenario({"robots": 2, "ticks": 10})
    warehouse = type(lab).from_mapping({**lab.to_mapping(), "warehouse": {}})
    geometry = simulate(warehouse, Proximity(), seed=0, runs=1, record=True).trajectories.geometry
    cells = _floor_cells(geometry)
    text = geometry.floor_text
    kinds = [kind for kind, *_ in cells]
    assert kinds.count("shelf") == text.count("#")
    assert kinds.count("pickup") == text.count("P")
    assert kinds.count("dropoff") == sum(text.count(d) for d in "0123456789")
    lines = text.splitlines()  # the first line is the top row
    assert ("shelf", 5 * 0.75, (len(lines) - 1 - 2) * 0.75, 0.75) in cells
    assert lines[2][5] == "#"
    assert _floor_cells(recorded_lab_geometry()) == ()


def recorded_lab_geometry():
    return simulate(
        scenario("tick"), Proximity(), seed=0, runs=1, record=True
    ).trajectories.geometry


def test_mcap_markers_are_one_byte_so_more_carriers_are_refused():
    from swarmtag.errors import ConfigError
    from swarmtag.sim.outputs.mcap import MCAP_MARKERS, check_mcap_carriers

    check_mcap_carriers(MCAP_MARKERS)  # markers 0-255
    with pytest.raises(ConfigError, match="one-byte marker ids"):
        check_mcap_carriers(MCAP_MARKERS + 1)
