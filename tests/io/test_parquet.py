"""Parquet: typed round trips, nulls, what other tools write, and the missing-extra message."""

from __future__ import annotations

import importlib

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq
import pytest
from hypothesis import HealthCheck, given, settings

from swarmtag.errors import EventLogError
from swarmtag.io import (
    EventTable,
    parse_carrier_csv,
    read_carrier_parquet,
    read_event_parquet,
    write_parquet,
)
from tests.io.strategies import carrier_logs
from tests.io.test_csv import GOOD


def test_round_trip_with_typed_columns_and_nulls(tmp_path):
    log = parse_carrier_csv(GOOD)
    path = tmp_path / "events.parquet"
    write_parquet(log, path)
    table = pq.read_table(path)
    assert table.schema.field("run").type == pa.int64()
    assert table.schema.field("condition").type == pa.string()
    assert table.column("delivery_time").to_pylist() == [52.7, None, 41.5]
    assert table.column("robot").to_pylist() == [1, None, 0]
    assert read_carrier_parquet(path) == log


@settings(max_examples=25, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(log=carrier_logs())
def test_any_log_round_trips(tmp_path, log):
    path = tmp_path / "any.parquet"
    write_parquet(log, path)
    assert read_carrier_parquet(path) == log


def _table(**changes):
    columns = {
        "condition": pa.array(["proximity", "proximity"]),
        "run": pa.array([0, 0], type=pa.int32()),
        "seed": pa.array([7, 7], type=pa.uint8()),
        "carrier": pa.array([3, 4]),
        "urgency0": pa.array([8, 0]),
        "order_time": pa.array([-213, 0], type=pa.int64()),
        "pickup_time": pa.array([37.1, float("nan")]),
        "delivery_time": pa.array([52.7, None]),
        # pandas writes an integer column with gaps as floats with NaN.
        "robot": pa.array([1.0, float("nan")]),
        "Notes": pa.array(["fine", None]),
    }
    columns.update(changes)
    return pa.table(columns)


def test_reads_what_other_tools_write(tmp_path):
    path = tmp_path / "pandas.parquet"
    pq.write_table(_table(condition=pa.array(["proximity", "proximity"]).dictionary_encode()), path)
    log = read_carrier_parquet(path)
    assert log.seed.tolist() == [7, 7]
    assert log.order_time.tolist() == [-213.0, 0.0]
    assert np.isnan(log.pickup_time[1])
    assert np.isnan(log.delivery_time[1])
    assert log.robot.tolist() == [1, -1]


@pytest.mark.parametrize(
    ("changes", "message"),
    [
        ({"run": pa.array(["0", "0"])}, "column run has type string; expected an integer"),
        ({"condition": pa.array([1, 2])}, "column condition has type int64; expected text"),
        ({"robot": pa.array([1.5, None])}, "row 1, column robot: 1.5 is not an integer"),
        ({"urgency0": pa.array([8, 10])}, "row 2, column urgency0: 10 is not an integer in 0-9"),
        ({"run": pa.array([0, None])}, "row 2, column run: is empty; expected an integer >= 0"),
        (
            {"robot": pa.array([-1, None])},
            "row 1, column robot: -1 is not an integer >= 0, or empty",
        ),
        (
            {"carrier": pa.array([3, 3])},
            "run 0 of proximity has two rows for carrier 3 (rows 1 and 2)",
        ),
    ],
)
def test_messages_name_file_row_and_column(tmp_path, changes, message):
    path = tmp_path / "bad.parquet"
    pq.write_table(_table(**changes), path)
    with pytest.raises(EventLogError) as error:
        read_carrier_parquet(path)
    assert str(error.value) == f"{path}: {message}"


def test_missing_columns_and_files(tmp_path):
    path = tmp_path / "short.parquet"
    pq.write_table(_table().drop_columns(["robot", "seed"]), path)
    with pytest.raises(EventLogError, match="lacks columns seed, robot"):
        read_carrier_parquet(path)
    with pytest.raises(EventLogError, match="no such file"):
        read_carrier_parquet(tmp_path / "missing.parquet")
    not_parquet = tmp_path / "text.parquet"
    not_parquet.write_text(GOOD)
    with pytest.raises(EventLogError, match="not a readable Parquet file"):
        read_carrier_parquet(not_parquet)


def test_time_unit_column(tmp_path):
    path = tmp_path / "unit.parquet"
    pq.write_table(_table(time_unit=pa.array(["s", None])), path)
    assert read_carrier_parquet(path).time_unit == "s"
    pq.write_table(_table(time_unit=pa.array(["s", "tick"])), path)
    with pytest.raises(EventLogError, match="holds s, tick; a log has one time unit"):
        read_carrier_parquet(path)


def test_event_table_round_trip(tmp_path):
    table = EventTable(
        condition=["proximity"] * 2,
        seed=[0, 0],
        run=[3, 3],
        time=[12.0, 40.0],
        kind=["select", "reprioritise"],
        carrier=[5, -1],
        robot=[1, -1],
        value=[float("nan"), 9.0],
    )
    path = tmp_path / "long.parquet"
    write_parquet(table, path)
    assert read_event_parquet(path) == table


def test_without_pyarrow_the_message_names_the_extra(tmp_path, monkeypatch):
    real_import = importlib.import_module

    def no_pyarrow(name, package=None):
        if name.startswith("pyarrow"):
            raise ImportError(name)
        return real_import(name, package)

    monkeypatch.setattr(importlib, "import_module", no_pyarrow)
    message = r"need the 'parquet' extra: pip install 'swarmtag\[parquet\]'"
    with pytest.raises(EventLogError, match=message):
        read_carrier_parquet(tmp_path / "x.parquet")
    with pytest.raises(EventLogError, match=message):
        write_parquet(parse_carrier_csv(GOOD), tmp_path / "x.parquet")
