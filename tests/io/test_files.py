"""Reading by extension, and the example trial log shipped as package data."""

from __future__ import annotations

from importlib.resources import files

import numpy as np
import pytest

from swarmtag.data import EXAMPLE_TRIAL, example_trial_path, example_trial_text
from swarmtag.errors import EventLogError
from swarmtag.io import (
    parse_carrier_csv,
    read_event_log,
    read_event_table,
    write_event_log,
    write_event_table,
)
from swarmtag.io.tables import EventTable
from tests.io.test_csv import GOOD


@pytest.mark.parametrize("name", ["events.csv", "events.CSV", "events.parquet", "events.pq"])
def test_round_trip_by_extension(tmp_path, name):
    log = parse_carrier_csv(GOOD)
    write_event_log(log, tmp_path / name)
    assert read_event_log(tmp_path / name) == log


@pytest.mark.parametrize("name", ["long.csv", "long.parquet"])
def test_event_table_by_extension(tmp_path, name):
    table = EventTable(
        condition=["c"],
        seed=[1],
        run=[2],
        time=[3.0],
        kind=["breakdown"],
        carrier=[-1],
        robot=[2],
        value=[float("nan")],
    )
    write_event_table(table, tmp_path / name)
    assert read_event_table(tmp_path / name) == table


def test_unknown_extension(tmp_path):
    with pytest.raises(
        EventLogError, match=r"events\.txt: unknown event-log format \.txt; expected"
    ):
        read_event_log(tmp_path / "events.txt")
    with pytest.raises(EventLogError, match=r"\(no extension\)"):
        write_event_log(parse_carrier_csv(GOOD), tmp_path / "events")


def test_example_trial_is_a_plausible_physical_trial():
    log = read_event_log(example_trial_path())
    assert log == parse_carrier_csv(example_trial_text())
    assert log == parse_carrier_csv(files("swarmtag.data").joinpath(EXAMPLE_TRIAL).read_text())
    assert log.time_unit == "s"
    assert log.conditions == ("proximity", "urgency:alpha=3.0")
    for condition in log.conditions:
        rows = log.condition == condition
        runs, per_run = np.unique(log.run[rows], return_counts=True)
        assert runs.tolist() == list(range(12))
        assert (per_run == 7).all()
    undelivered = int(np.isnan(log.delivery_time).sum())
    assert 1 <= undelivered <= 4
    assert (log.order_time <= 0).all()
    # Static urgency model: order time precedes the start by (u / 9) * 240 s (to 0.1 s).
    np.testing.assert_allclose(log.order_time, -log.urgency0 / 9 * 240, atol=0.051)


def test_failed_write_leaves_the_old_file_and_no_temporary(tmp_path, monkeypatch):
    from swarmtag.errors import EventLogError
    from swarmtag.io import write_event_log
    from swarmtag.io.csv_format import parse_carrier_csv

    path = tmp_path / "events.csv"
    path.write_text("old contents\n")
    log = parse_carrier_csv(
        "condition,run,seed,carrier,urgency0,order_time,pickup_time,delivery_time,robot\n"
        "proximity,0,0,1,3,-2,1,4,0\n"
    )

    def refuse(self, target):
        raise OSError(28, "No space left on device")

    monkeypatch.setattr("pathlib.Path.replace", refuse)
    with pytest.raises(EventLogError, match="cannot write"):
        write_event_log(log, path)
    assert path.read_text() == "old contents\n"
    assert [p.name for p in tmp_path.iterdir()] == ["events.csv"]
