"""The public event-log functions refuse wrong arguments with ``EventLogError`` (issue 35, item 7).

Each call here once escaped as a bare ``TypeError``, ``AttributeError`` or
``ValueError`` from deep inside (``os.fspath``, numpy, the CSV writer).
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from swarmtag.data import example_trial_path
from swarmtag.errors import EventLogError
from swarmtag.io import (
    CarrierLog,
    EventTable,
    format_csv,
    parse_carrier_csv,
    parse_event_csv,
    read_carrier_csv,
    read_carrier_parquet,
    read_event_csv,
    read_event_log,
    read_event_parquet,
    read_event_table,
    write_csv,
    write_event_log,
    write_event_table,
    write_parquet,
)

LOG = read_event_log(example_trial_path())
HUGE = pytest.param(10**5000, id="10**5000")
BAD_PATHS = [None, 3, math.nan, np.int64(-3), ["a.csv"], {}, "", "a\0.csv", Path("a\0.csv")]
NOT_TABLES = [None, 1.5, "log.csv", [LOG], {}, np.array([1.0])]


@pytest.mark.parametrize(
    "read",
    [
        read_carrier_csv,
        read_event_csv,
        read_carrier_parquet,
        read_event_parquet,
        read_event_log,
        read_event_table,
    ],
)
@pytest.mark.parametrize("path", BAD_PATHS)
def test_readers_refuse_what_is_no_path(read, path):
    with pytest.raises(EventLogError, match=r"^path: .* is not a path"):
        read(path)


@pytest.mark.parametrize("write", [write_csv, write_parquet, write_event_log])
@pytest.mark.parametrize("path", BAD_PATHS)
def test_writers_refuse_what_is_no_path(write, path, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    with pytest.raises(EventLogError, match=r"^path: .* is not a path"):
        write(LOG, path)
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize(
    ("write", "name"),
    [
        (write_csv, "table"),
        (write_parquet, "table"),
        (write_event_log, "log"),
        (write_event_table, "table"),
    ],
)
@pytest.mark.parametrize("table", NOT_TABLES)
def test_writers_refuse_what_is_no_table(write, name, table, tmp_path):
    with pytest.raises(EventLogError, match=rf"^{name}: .* is not a (CarrierLog|EventTable)"):
        write(table, tmp_path / "out.csv")
    assert list(tmp_path.iterdir()) == []


def test_write_event_table_refuses_a_carrier_log(tmp_path):
    with pytest.raises(EventLogError, match=r"^table: .* is not a EventTable"):
        write_event_table(LOG, tmp_path / "out.csv")


@pytest.mark.parametrize("table", NOT_TABLES)
def test_format_csv_refuses_what_is_no_table(table):
    with pytest.raises(EventLogError, match=r"^table: .* is not a CarrierLog or EventTable"):
        format_csv(table)


@pytest.mark.parametrize("parse", [parse_carrier_csv, parse_event_csv])
@pytest.mark.parametrize("text", [None, HUGE, b"condition\n", ["a,b"], math.nan])
def test_parsers_refuse_text_that_is_no_string(parse, text):
    with pytest.raises(EventLogError, match=r"^text: .* is not a string"):
        parse(text)


@pytest.mark.parametrize("parse", [parse_carrier_csv, parse_event_csv])
@pytest.mark.parametrize("source", [3, HUGE, np.array([]), Path("x.csv")])
def test_parsers_refuse_a_source_that_is_no_string(parse, source):
    with pytest.raises(EventLogError, match=r"^source: .* is not a string"):
        parse(format_csv(LOG), source=source)


@pytest.mark.parametrize("table", [CarrierLog, EventTable])
@pytest.mark.parametrize(
    "tables", [None, 3, 2.5, "log", [1, 2], [[LOG]], np.array([]), np.array([1.0, 2.0])]
)
def test_concat_refuses_what_is_no_list_of_tables(table, tables):
    with pytest.raises(EventLogError, match=r"tables"):
        table.concat(tables)


def test_concat_refuses_a_table_of_the_other_kind():
    with pytest.raises(EventLogError, match=r"^tables: .* is not a EventTable"):
        EventTable.concat([LOG])


def test_good_calls_still_work(tmp_path):
    write_event_log(LOG, str(tmp_path / "log.csv"))
    assert read_event_log(tmp_path / "log.csv") == LOG
    assert parse_carrier_csv(format_csv(LOG), source="x.csv") == LOG
    assert CarrierLog.concat((LOG,)) == CarrierLog.concat([LOG]) == LOG
