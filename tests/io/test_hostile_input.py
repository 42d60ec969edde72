"""Hostile event logs: each is refused with one EventLogError line naming file, row and column."""

from __future__ import annotations

import json
import math
import os
import sys

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from swarmtag.cli import main
from swarmtag.errors import EventLogError
from swarmtag.io import (
    MAX_EVENT_TIME,
    MIN_NONZERO_TIME,
    TIME_COLUMNS,
    CarrierLog,
    EventTable,
    parse_carrier_csv,
    parse_event_csv,
    read_carrier_csv,
    read_carrier_parquet,
    read_event_log,
    read_event_table,
    write_event_log,
)
from tests.io.test_csv import GOOD, HEADER

# GOOD's line 2 is: proximity,0,7,3,8,-213.3,37.1,52.7,1


def refused(text: str, message: str) -> None:
    with pytest.raises(EventLogError) as error:
        parse_carrier_csv(text, source="events.csv")
    assert str(error.value).startswith(message), str(error.value)
    assert "\n" not in str(error.value)


def test_the_time_columns_are_listed():
    assert TIME_COLUMNS == ("order_time", "pickup_time", "delivery_time", "run_end", "time")
    assert MAX_EVENT_TIME == 1e12


@pytest.mark.parametrize(
    ("cell", "shown"),
    [
        ("1e308", "1e+308"),
        ("1000000000000.0001", "1000000000000.0001"),
        ("-1", "-1.0"),
        ("1e400", "'1e400'"),
    ],
)
def test_a_time_out_of_range_is_refused_with_the_range(cell, shown):
    refused(
        GOOD.replace("37.1,52.7", f"37.1,{cell}"),
        f"events.csv: line 2, column delivery_time: {shown} is out of range; "
        "expected a number in [0, 1e+12], or empty",
    )


def test_order_time_may_precede_the_run_start_but_not_by_more_than_the_range():
    assert parse_carrier_csv(GOOD.replace("-213.3", "-1e12")).order_time[0] == -1e12
    refused(
        GOOD.replace("-213.3", "-1.5e12"),
        "events.csv: line 2, column order_time: -1500000000000.0 is out of range; "
        "expected a number in [-1e+12, 1e+12]",
    )


def test_a_time_closer_to_zero_than_the_resolution_is_refused():
    assert parse_carrier_csv(GOOD.replace("37.1,", f"{MIN_NONZERO_TIME!r},")).pickup_time[0] == 1e-9
    refused(
        GOOD.replace("37.1,", "5e-324,"),
        "events.csv: line 2, column pickup_time: 5e-324 is too close to 0",
    )


def test_event_table_times_and_values_have_ranges():
    text = "condition,seed,run,time,kind,carrier,robot,value\nproximity,0,3,12.0,select,5,1,\n"
    assert len(parse_event_csv(text)) == 1
    with pytest.raises(EventLogError, match=r"^line 2, column time: 1e\+300 is out of range"):
        parse_event_csv(text.replace("12.0", "1e300"))
    with pytest.raises(
        EventLogError, match=r"^line 2, column value: 10000000000000\.0 is out of range"
    ):
        parse_event_csv(text.replace("1,\n", "1,1e13\n"))


def test_order_time_after_pickup_or_delivery_is_refused():
    refused(
        GOOD.replace("-213.3", "40"),
        "events.csv: line 2, column pickup_time: 37.1 is before order_time 40.0",
    )
    refused(
        GOOD.replace("-213.3,37.1", "60,"),
        "events.csv: line 2, column delivery_time: 52.7 is before order_time 60.0",
    )
    # A carrier never picked up may be ordered at any time of the run.
    assert parse_carrier_csv(GOOD.replace("7,0,0,,,", "7,0,500,,,")).order_time[1] == 500.0


def test_order_time_after_run_end_is_refused():
    text = (
        GOOD.replace(HEADER, HEADER + ",run_end")
        .replace("52.7,1\n", "52.7,1,60\n")
        .replace(",,,\n", ",,,,60\n")
        .replace("41.5,0\n", "41.5,0,\n")
    )
    assert parse_carrier_csv(text).run_end[0] == 60.0
    refused(
        text.replace("7,0,0,,,", "7,0,61,,,"),
        "events.csv: line 3, column run_end: 60.0 is before order_time 61.0",
    )
    refused(
        text.replace("52.7,1,60", "52.7,1,52").replace(",,,,60", ",,,,52"),
        "events.csv: line 2, column run_end: 52.0 is before delivery_time 52.7",
    )


@pytest.mark.parametrize(
    ("old", "new", "message"),
    [
        ("52.7,1", "12\x00,1", "events.csv: line 2, column delivery_time: '12\\x00' holds a NUL"),
        ("proximity,0,7,3", "prox\x00imity,0,7,3", "events.csv: line 2, column condition: "),
        (
            "52.7,1\n",
            "52.7,1,\x00\n",
            "events.csv: line 2, column 10 (unnamed): '\\x00' holds a NUL",
        ),
        ("robot\n", "robot,no\x00tes\n", "events.csv: line 1, column 10 of the header holds a NUL"),
    ],
)
def test_a_nul_byte_anywhere_is_refused(old, new, message):
    assert old in GOOD
    refused(GOOD.replace(old, new, 1), message)


@pytest.mark.parametrize(
    "cell",
    [
        "1_000",
        "infinity",
        "inf",
        "nan",
        "NaN",
        "\u0661\u0662",
        "\uff11\uff12",
        "1 2",
        "0x10",
        "1e",
        "--1",
        "1.2.3",
    ],
)
def test_numbers_python_reads_but_that_are_not_plain_are_refused(cell):
    with pytest.raises(EventLogError, match=r"^events\.csv: line 2, column delivery_time: '"):
        parse_carrier_csv(GOOD.replace("37.1,52.7", f"37.1,{cell}"), source="events.csv")
    with pytest.raises(EventLogError, match=r"^line 2, column robot: '.*' is not an integer"):
        parse_carrier_csv(GOOD.replace("52.7,1", f"52.7,{cell}"))


@pytest.mark.parametrize(
    ("cell", "value"),
    [
        (" 52 ", 52.0),
        ("+52", 52.0),
        ("52.", 52.0),
        ("5.2e1", 52.0),
        ("5.2E+1", 52.0),
        ("052", 52.0),
    ],
)
def test_plain_numbers_are_read(cell, value):
    assert parse_carrier_csv(GOOD.replace("52.7,1", f"{cell},1")).delivery_time[0] == value


@pytest.mark.parametrize(("cell", "value"), [("3.0", 3), ("3.", 3), ("+3", 3), ("003", 3)])
def test_plain_integers_are_read(cell, value):
    assert parse_carrier_csv(GOOD.replace("52.7,1", f"52.7,{cell}")).robot[0] == value


@pytest.mark.parametrize("cell", ["3.5", "1e3", "3.01", ".0"])
def test_integers_with_a_fraction_or_exponent_are_refused(cell):
    refused(GOOD.replace("52.7,1", f"52.7,{cell}"), "events.csv: line 2, column robot: ")


def test_control_characters_in_text_are_refused():
    refused(
        GOOD.replace("proximity,0,7,3", "prox\x1b[31mimity,0,7,3"),
        "events.csv: line 2, column condition: 'prox\\x1b[31mimity' holds control character",
    )
    refused(
        GOOD.replace("proximity,0,7,3", '"two\nlines",0,7,3'),
        "events.csv: line 2, column condition: 'two\\nlines' holds control character '\\n'",
    )
    with pytest.raises(EventLogError, match="row 1, column condition: 'a\\\\x00' holds a NUL"):
        CarrierLog(**{**parse_carrier_csv(GOOD).take([0]).columns(), "condition": ["a\x00"]})


@pytest.mark.skipif(sys.platform == "win32", reason="no FIFOs")
@pytest.mark.parametrize("name", ["events.csv", "events.parquet"])
def test_a_fifo_is_refused_without_blocking(tmp_path, name):
    path = tmp_path / name
    os.mkfifo(path)
    for read in (read_event_log, read_event_table):
        with pytest.raises(EventLogError, match="is not a regular file"):
            read(path)
    folder = tmp_path / f"folder{path.suffix}"
    folder.mkdir()
    with pytest.raises(EventLogError, match="is a folder"):
        read_event_log(folder)


@pytest.mark.parametrize("column", ["run", "seed", "carrier", "robot"])
def test_integers_beyond_int64_are_refused_with_the_range(tmp_path, column):
    log = parse_carrier_csv(GOOD)
    big = 2**64 + 5
    message = f"is too large; expected an integer in 0-{2**63 - 1}"
    columns = {**log.columns(), column: [big, 0, 0]}
    with pytest.raises(EventLogError, match=rf"^row 1, column {column}: {big} {message}"):
        CarrierLog(**columns)
    path = _parquet(tmp_path, **{column: pa.array([2**63, 0, 0], type=pa.uint64())})
    with pytest.raises(EventLogError, match=rf"row 1, column {column}: {2**63} {message}"):
        read_carrier_parquet(path)
    path = _parquet(tmp_path, **{column: pa.array([1e19, 0.0, 0.0])})
    with pytest.raises(EventLogError, match=rf"row 1, column {column}: 1e\+19 {message}"):
        read_carrier_parquet(path)


def test_a_huge_digit_string_is_refused_not_overflowed():
    refused(GOOD.replace("7,3,8", "9" * 5000 + ",3,8"), "events.csv: line 2, column seed: '999")


def _parquet(tmp_path, **changes):
    """GOOD as a Parquet file, with some columns replaced by the given Arrow arrays."""
    path = tmp_path / "events.parquet"
    write_event_log(parse_carrier_csv(GOOD), path)
    table = pq.read_table(path)
    for name, array in changes.items():
        table = table.set_column(table.schema.get_field_index(name), name, array)
    pq.write_table(table, path)
    return path


@pytest.mark.parametrize(
    ("change", "message"),
    [
        ({"delivery_time": pa.array([math.inf, None, 41.5])}, "row 1, column delivery_time: inf"),
        ({"delivery_time": pa.array([1e308, None, 41.5])}, "row 1, column delivery_time: 1e+308"),
        ({"order_time": pa.array([40.0, 0.0, 0.0])}, "row 1, column pickup_time: 37.1 is before"),
        ({"condition": pa.array(["a\x00", "b", "c"])}, "row 1, column condition: 'a\\x00' holds"),
        ({"pickup_time": pa.array([-1.0, None, 20.0])}, "row 1, column pickup_time: -1.0 is out"),
    ],
)
def test_parquet_values_meet_the_same_rules(tmp_path, change, message):
    with pytest.raises(EventLogError) as error:
        read_carrier_parquet(_parquet(tmp_path, **change))
    assert message in str(error.value)


@pytest.mark.parametrize(
    "mangle",
    [
        lambda data: data[: len(data) // 2],
        lambda data: data[:-12] + b"\xff" * 8 + data[-4:],
        lambda data: b"PAR1" + b"\x00" * 64 + b"PAR1",
        lambda data: b"PAR1" + bytes(range(256)) * 4 + data[-8:],
    ],
)
def test_a_corrupt_parquet_file_is_one_line(tmp_path, mangle):
    path = _parquet(tmp_path)
    path.write_bytes(mangle(path.read_bytes()))
    with pytest.raises(EventLogError) as error:
        read_carrier_parquet(path)
    assert str(error.value).startswith(f"{path}: ")
    assert "\n" not in str(error.value)


def test_a_field_above_the_csv_size_limit_is_one_line(tmp_path):
    path = tmp_path / "long.csv"
    path.write_text(GOOD.replace("52.7,1\n", '52.7,1,"' + "x" * 200_000 + '"\n'), encoding="utf-8")
    with pytest.raises(EventLogError, match=r"long\.csv: line 2: not valid CSV \(field larger"):
        read_carrier_csv(path)


def test_memory_errors_become_one_line(monkeypatch):
    def exhausted(*_args: object) -> None:
        raise MemoryError

    monkeypatch.setattr("swarmtag.io.csv_format._rows", exhausted)
    with pytest.raises(EventLogError, match=r"^big\.csv: too large to read \(out of memory\)$"):
        parse_carrier_csv(GOOD, source="big.csv")


def _strict_json(text: str) -> object:
    def refuse(constant: str) -> object:
        raise AssertionError(f"non-finite {constant} in the JSON")

    return json.loads(text, parse_constant=refuse)


def test_metrics_json_is_finite_at_the_extreme_allowed_times(tmp_path, capsys):
    top, below = MAX_EVENT_TIME, float(np.nextafter(MAX_EVENT_TIME, 0))
    tiny, next_tiny = MIN_NONZERO_TIME, float(np.nextafter(MIN_NONZERO_TIME, 1))
    rows = []
    for run in range(4):
        for carrier, (pickup, delivery) in enumerate(
            [(top, top), (below, below), (0.0, tiny), (tiny, next_tiny), (0.0, 0.0), (None, None)]
        ):
            rows.append((f"c{run % 2}", run, carrier, pickup, delivery))
    n = len(rows)
    log = CarrierLog(
        condition=[row[0] for row in rows],
        run=[row[1] for row in rows],
        seed=[2**63 - 1] * n,
        carrier=[row[2] for row in rows],
        urgency0=[9] * n,
        order_time=[-top] * n,
        pickup_time=[math.nan if row[3] is None else row[3] for row in rows],
        delivery_time=[math.nan if row[4] is None else row[4] for row in rows],
        robot=[-1 if row[4] is None else 2**63 - 1 for row in rows],
        run_end=[top] * n,
    )
    path = tmp_path / "extreme.csv"
    write_event_log(log, path)
    with pytest.raises(SystemExit) as exit_info:
        main(["metrics", str(path), "--json", "--resamples", "50"])
    out, err = capsys.readouterr()
    assert (exit_info.value.code, err) == (0, "")
    report = _strict_json(out)
    assert isinstance(report, dict)
    assert len(report["conditions"]) == 2


CELLS = st.one_of(
    st.text(max_size=12),
    st.sampled_from(["1e308", "-1e308", "nan", "inf", "1_0", "\x00", "9" * 30, "5e-324", "", "-0"]),
    st.integers(-(2**70), 2**70).map(str),
    st.floats(allow_nan=True, allow_infinity=True).map(repr),
)


@settings(max_examples=150, deadline=None)
@given(st.data())
def test_any_cell_in_a_csv_reads_or_is_an_event_log_error(data):
    lines = GOOD.splitlines()
    line = data.draw(st.integers(0, len(lines) - 1))
    cells = lines[line].split(",")
    column = data.draw(st.integers(0, len(cells) - 1))
    cells[column] = data.draw(CELLS)
    lines[line] = ",".join(cells)
    text = "\n".join(lines) + "\n"
    try:
        log = parse_carrier_csv(text, source="fuzz.csv")
    except EventLogError as error:
        message = str(error)
    else:
        message = None
    if message is not None:
        assert "\n" not in message
        return
    for name in TIME_COLUMNS[:4]:
        values = getattr(log, name)
        assert np.all(np.isnan(values) | (np.abs(values) <= MAX_EVENT_TIME))


@settings(
    max_examples=100, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture]
)
@given(st.binary(max_size=400), st.sampled_from(["fuzz.csv", "fuzz.parquet"]))
def test_any_bytes_read_or_are_an_event_log_error(tmp_path, payload, name):
    path = tmp_path / name
    prefix = GOOD.encode() if name.endswith(".csv") and payload[:1] == b"+" else b""
    path.write_bytes(prefix + payload)
    for read in (read_event_log, read_event_table):
        message = f"{path}: read"
        try:
            read(path)
        except EventLogError as error:
            message = str(error)
        assert message.startswith(f"{path}: ")
        assert "\n" not in message


@settings(
    max_examples=60, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture]
)
@given(st.binary(min_size=1, max_size=64), st.integers(0, 10_000))
def test_parquet_with_bytes_overwritten_reads_or_is_an_event_log_error(tmp_path, junk, at):
    path = _parquet(tmp_path)
    data = bytearray(path.read_bytes())
    at %= len(data)
    data[at : at + len(junk)] = junk
    path.write_bytes(bytes(data))
    message = ""
    try:
        read_carrier_parquet(path)
    except EventLogError as error:
        message = str(error)
    assert "\n" not in message


def test_in_memory_event_times_have_the_same_range():
    with pytest.raises(EventLogError, match=r"^row 1, column time: -3\.0 is out of range"):
        EventTable(
            condition=["c"],
            seed=[0],
            run=[0],
            time=[-3.0],
            kind=["select"],
            carrier=[1],
            robot=[0],
            value=[1.0],
        )


def test_a_long_list_of_rows_is_cut_to_five_in_the_message():
    from swarmtag.data import example_trial_path
    from swarmtag.io import CarrierLog, read_event_log

    log = read_event_log(example_trial_path())
    with pytest.raises(EventLogError) as error:
        CarrierLog.concat([log] * 40)
    message = str(error.value)
    assert "has 40 rows for carrier" in message
    assert message.endswith(", ... (40 in all))")
