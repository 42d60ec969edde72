"""CSV: what spreadsheets write, canonical output, round trips, messages with file/line/column."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from swarmtag.errors import EventLogError
from swarmtag.io import (
    MAX_EVENT_TIME,
    MIN_NONZERO_TIME,
    CarrierLog,
    EventTable,
    format_csv,
    parse_carrier_csv,
    parse_event_csv,
    read_carrier_csv,
    read_event_csv,
    write_csv,
)
from tests.io.strategies import carrier_logs

HEADER = "condition,run,seed,carrier,urgency0,order_time,pickup_time,delivery_time,robot"
GOOD = f"""{HEADER}
proximity,0,7,3,8,-213.3,37.1,52.7,1
proximity,0,7,7,0,0,,,
proximity,1,7,3,2,-53.3,20,41.5,0
"""


def test_reads_a_plain_log():
    log = parse_carrier_csv(GOOD)
    assert log.run.tolist() == [0, 0, 1]
    assert log.order_time.tolist() == [-213.3, 0.0, -53.3]
    assert np.isnan(log.delivery_time[1])
    assert log.robot.tolist() == [1, -1, 0]
    assert log.time_unit is None


def test_reads_what_a_spreadsheet_writes():
    # BOM, CRLF, spaces around cells and names, header in another case, columns in another
    # order, an extra column, blank rows (also as empty cells) and a time unit on some rows.
    text = (
        "\ufeff Robot , Condition,run,seed,carrier,urgency0,order_time,pickup_time,"
        "delivery_time,notes,time_unit\r\n"
        '1, proximity ,0,7,3,8, -213.3 ,37.1,52.7,"late, but fine",s\r\n'
        "\r\n"
        ",proximity,0,7,7,0,0,,,,\r\n"
        ",,,,,,,,,,\r\n"
    )
    expected = CarrierLog(**parse_carrier_csv(GOOD).take([0, 1]).columns(), time_unit="s")
    assert parse_carrier_csv(text) == expected


def test_semicolon_and_tab_separated_files():
    for separator in (";", "\t"):
        assert parse_carrier_csv(GOOD.replace(",", separator)) == parse_carrier_csv(GOOD)


def test_integral_decimals_are_integers():
    log = parse_carrier_csv(GOOD.replace("proximity,1,7,3,2", "proximity,1.0,7,3,2.0"))
    assert log.run.tolist() == [0, 0, 1]


@pytest.mark.parametrize(
    ("old", "new", "message"),
    [
        (
            "37.1,52.7",
            "37.1,abc",
            "events.csv: line 2, column delivery_time: 'abc' is not a number",
        ),
        (
            "0,7,3,8,",
            "0,7,3,12,",
            "events.csv: line 2, column urgency0: 12 is not an integer in 0-9",
        ),
        ("0,7,3,8,", "0,7,3,8.5,", "events.csv: line 2, column urgency0: '8.5' is not an integer"),
        ("proximity,1,", ",1,", "events.csv: line 4, column condition: is empty; expected text"),
        ("-53.3,20", ",20", "events.csv: line 4, column order_time: is empty; expected a number"),
        ("-53.3,20", "nan,20", "events.csv: line 4, column order_time: 'nan' is not a finite"),
        (
            "41.5,0",
            "41.5,-1",
            "events.csv: line 4, column robot: -1 is not an integer >= 0, or empty",
        ),
        ("41.5,0", "41.5,", "events.csv: line 4, column robot: is empty but the carrier was"),
        (
            "20,41.5",
            "50,41.5",
            "events.csv: line 4, column delivery_time: 41.5 is before pickup_time",
        ),
        (
            "proximity,0,7,7",
            "proximity,0,7,3",
            "events.csv: run 0 of proximity has two rows for carrier 3 (lines 2 and 3)",
        ),
        (
            "proximity,0,7,7",
            "proximity,0,8,7",
            "events.csv: line 3, column seed: 8 differs from seed 7 on line 2",
        ),
        ("41.5,0\n", "41.5,0,extra\n", "events.csv: line 4 has 10 cells but the header names 9"),
        (
            "7,3,8",
            "99999999999999999999,3,8",
            "events.csv: line 2, column seed: '99999999999999999999' is too large",
        ),
    ],
)
def test_messages_name_file_line_and_column(old, new, message):
    assert old in GOOD
    with pytest.raises(EventLogError) as error:
        parse_carrier_csv(GOOD.replace(old, new, 1), source="events.csv")
    assert str(error.value).startswith(message)


def test_line_numbers_count_blank_rows_and_quoted_newlines():
    # Lines: 1 header, 2-3 data, 4 blank, 5-6 one row whose notes cell spans two lines, 7 data.
    text = (
        GOOD.replace(HEADER, HEADER + ",notes")
        .replace("\nproximity,1,", "\n\nproximity,1,")
        .replace("41.5,0\n", '41.5,0,"multi\nline"\n')
        + "proximity,2,7,3,2,0,,,,\n"
    )
    with pytest.raises(EventLogError, match=r"^line 5, column robot: 'x' is not an integer"):
        parse_carrier_csv(text.replace("41.5,0", "41.5,x"))
    with pytest.raises(EventLogError, match=r"^line 7, column urgency0: 12 is not an integer"):
        parse_carrier_csv(text.replace("proximity,2,7,3,2", "proximity,2,7,3,12"))
    with pytest.raises(EventLogError, match=r"^line 4, column robot: 'y' is not an integer"):
        parse_carrier_csv("\n\n" + GOOD.replace("52.7,1", "52.7,y"))


def test_header_problems():
    with pytest.raises(
        EventLogError, match="line 1 lacks columns pickup_time, robot; an event log"
    ):
        parse_carrier_csv(GOOD.replace("pickup_time", "pickup").replace(",robot", ",who"))
    with pytest.raises(EventLogError, match="line 1 names column run more than once"):
        parse_carrier_csv(GOOD.replace("condition,", "run,", 1))
    with pytest.raises(EventLogError, match="is empty; expected a header line"):
        parse_carrier_csv("\n \n")


def test_time_unit_must_be_one_and_known():
    text = GOOD.replace(HEADER, HEADER + ",time_unit").replace("52.7,1\n", "52.7,1,s\n")
    assert parse_carrier_csv(text).time_unit == "s"
    assert parse_carrier_csv(text.replace(",s\n", ",S\n")).time_unit == "s"
    with pytest.raises(EventLogError, match=r"line 2, column time_unit: 'min' is not tick or s"):
        parse_carrier_csv(text.replace(",s\n", ",min\n"))
    mixed = text.replace("41.5,0\n", "41.5,0,tick\n")
    with pytest.raises(EventLogError, match=r"line 4, column time_unit: 'tick' differs from 's'"):
        parse_carrier_csv(mixed)


def test_canonical_format_is_fixed():
    log = parse_carrier_csv(GOOD)
    assert format_csv(log) == (
        f"{HEADER}\n"
        "proximity,0,7,3,8,-213.3,37.1,52.7,1\n"
        "proximity,0,7,7,0,0.0,,,\n"
        "proximity,1,7,3,2,-53.3,20.0,41.5,0\n"
    )
    with_unit = CarrierLog(**log.columns(), time_unit="tick")
    assert format_csv(with_unit).splitlines()[:2] == [
        f"{HEADER},time_unit",
        "proximity,0,7,3,8,-213.3,37.1,52.7,1,tick",
    ]


def test_floats_are_written_as_repr():
    values = [0.1, 1e-05, 1e11, 2.5e-09, 123456789.123, -0.0]
    log = CarrierLog(
        condition=["c"] * 6,
        run=range(6),
        seed=[0] * 6,
        carrier=[0] * 6,
        urgency0=[0] * 6,
        order_time=values,
        pickup_time=[float("nan")] * 6,
        delivery_time=[float("nan")] * 6,
        robot=[-1] * 6,
    )
    cells = [line.split(",")[5] for line in format_csv(log).splitlines()[1:]]
    assert cells == [repr(v) for v in values]
    assert parse_carrier_csv(format_csv(log)).order_time.tolist() == values


@given(carrier_logs())
def test_round_trip_is_exact_and_bytes_are_stable(log):
    text = format_csv(log)
    again = parse_carrier_csv(text)
    assert again == log
    assert format_csv(again) == text


@given(
    st.lists(
        st.floats(-MAX_EVENT_TIME, MAX_EVENT_TIME).filter(
            lambda v: v == 0 or abs(v) >= MIN_NONZERO_TIME
        ),
        min_size=1,
        max_size=20,
    )
)
def test_any_allowed_time_survives_a_round_trip(values):
    n = len(values)
    log = CarrierLog(
        condition=["c"] * n,
        run=range(n),
        seed=[0] * n,
        carrier=[0] * n,
        urgency0=[0] * n,
        order_time=values,
        pickup_time=[float("nan")] * n,
        delivery_time=[float("nan")] * n,
        robot=[-1] * n,
    )
    assert (
        parse_carrier_csv(format_csv(log)).order_time.tobytes()
        == np.asarray(values, dtype=np.float64).tobytes()
    )


def test_files(tmp_path):
    log = parse_carrier_csv(GOOD)
    path = tmp_path / "events.csv"
    write_csv(log, path)
    assert path.read_bytes() == format_csv(log).encode("utf-8")
    assert read_carrier_csv(path) == log
    assert read_carrier_csv(str(path)) == log


def test_file_problems(tmp_path):
    with pytest.raises(EventLogError, match=r"missing\.csv: no such file"):
        read_carrier_csv(tmp_path / "missing.csv")
    with pytest.raises(EventLogError, match="is a folder, not the CSV event log"):
        read_carrier_csv(tmp_path)
    latin = tmp_path / "latin.csv"
    latin.write_bytes(GOOD.replace("proximity", "proximit\xe9").encode("latin-1"))
    with pytest.raises(EventLogError, match=r"latin\.csv: not UTF-8 text"):
        read_carrier_csv(latin)
    nul = tmp_path / "nul.csv"
    nul.write_text(GOOD + "a\0b,1\n", encoding="utf-8")
    with pytest.raises(EventLogError, match=r"nul\.csv: "):
        read_carrier_csv(nul)
    with pytest.raises(EventLogError, match="cannot write"):
        write_csv(parse_carrier_csv(GOOD), tmp_path / "no" / "such" / "dir.csv")


def test_event_table_round_trip(tmp_path):
    table = EventTable(
        condition=["proximity"] * 3,
        seed=[0] * 3,
        run=[3] * 3,
        time=[12.0, 40.0, 41.0],
        kind=["select", "reprioritise", "abandon"],
        carrier=[5, 5, 5],
        robot=[1, -1, 1],
        value=[float("nan"), 9.0, float("nan")],
        time_unit="tick",
    )
    text = format_csv(table)
    assert text.splitlines() == [
        "condition,seed,run,time,kind,carrier,robot,value,time_unit",
        "proximity,0,3,12.0,select,5,1,,tick",
        "proximity,0,3,40.0,reprioritise,5,,9.0,tick",
        "proximity,0,3,41.0,abandon,5,1,,tick",
    ]
    assert parse_event_csv(text) == table
    path = tmp_path / "events_long.csv"
    write_csv(table, path)
    assert read_event_csv(path) == table
    with pytest.raises(EventLogError, match="line 3, column robot: 'r2' is not an integer"):
        parse_event_csv(text.replace("5,,9.0", "5,r2,9.0"))
