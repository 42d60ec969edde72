"""The optional carrier columns run_end and urgency_end: absent, present, checked, round trips."""

from __future__ import annotations

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq
import pytest

from swarmtag.errors import EventLogError
from swarmtag.io import (
    CarrierLog,
    format_csv,
    parse_carrier_csv,
    read_carrier_parquet,
    read_event_log,
    write_event_log,
    write_parquet,
)
from tests.io.test_csv import GOOD, HEADER

WITH_ENDS = f"""{HEADER},run_end,urgency_end
proximity,0,7,3,8,-213.3,37.1,52.7,1,60.0,9
proximity,0,7,7,0,0.0,,,,60.0,4
proximity,1,7,3,2,-53.3,20.0,41.5,0,,
"""


def test_a_log_without_them_reads_as_empty_and_writes_byte_identically():
    log = parse_carrier_csv(GOOD)
    assert np.isnan(log.run_end).all()
    assert log.urgency_end.tolist() == [-1, -1, -1]
    # Exactly the text written before the optional columns existed.
    assert format_csv(log) == (
        f"{HEADER}\n"
        "proximity,0,7,3,8,-213.3,37.1,52.7,1\n"
        "proximity,0,7,7,0,0.0,,,\n"
        "proximity,1,7,3,2,-53.3,20.0,41.5,0\n"
    )
    assert [spec.name for spec in log.written_columns()] == HEADER.split(",")


def test_csv_with_them_round_trips():
    log = parse_carrier_csv(WITH_ENDS)
    assert log.run_end.tolist()[:2] == [60.0, 60.0]
    assert np.isnan(log.run_end[2])  # run 1 states no end
    assert log.urgency_end.tolist() == [9, 4, -1]
    assert format_csv(log) == WITH_ENDS
    assert parse_carrier_csv(format_csv(log)) == log


def test_only_the_columns_with_a_value_are_written():
    log = CarrierLog(**{**parse_carrier_csv(GOOD).columns(), "urgency_end": [1, 2, 3]})
    header = format_csv(log).splitlines()[0]
    assert header == f"{HEADER},urgency_end"
    with_unit = CarrierLog(**{**log.columns(), "run_end": [60.0, 60.0, 50.0]}, time_unit="s")
    assert format_csv(with_unit).splitlines()[0] == f"{HEADER},run_end,urgency_end,time_unit"


def test_columns_in_any_order_and_case_with_blank_cells():
    text = (
        "URGENCY_END,run_end," + HEADER + "\n"
        "9,60," + GOOD.splitlines()[1] + "\n"
        ",60," + GOOD.splitlines()[2] + "\n"
    )
    log = parse_carrier_csv(text)
    assert log.urgency_end.tolist() == [9, -1]
    assert log.run_end.tolist() == [60.0, 60.0]


def test_parquet_with_and_without_them(tmp_path):
    plain = parse_carrier_csv(GOOD)
    path = tmp_path / "plain.parquet"
    write_parquet(plain, path)
    assert "run_end" not in pq.read_table(path).column_names
    assert read_carrier_parquet(path) == plain
    log = parse_carrier_csv(WITH_ENDS)
    path = tmp_path / "ends.parquet"
    write_event_log(log, path)
    table = pq.read_table(path)
    assert table.column("run_end").to_pylist() == [60.0, 60.0, None]
    assert table.column("urgency_end").to_pylist() == [9, 4, None]
    assert table.schema.field("urgency_end").type == pa.int64()
    assert read_event_log(path) == log


def test_parquet_as_pandas_writes_it(tmp_path):
    # An integer column with gaps comes as floats with NaN.
    table = pq.read_table(_written(tmp_path, parse_carrier_csv(WITH_ENDS)))
    index = table.column_names.index("urgency_end")
    table = table.set_column(index, "urgency_end", pa.array([9.0, 4.0, float("nan")]))
    path = tmp_path / "pandas.parquet"
    pq.write_table(table, path)
    assert read_carrier_parquet(path).urgency_end.tolist() == [9, 4, -1]


def _written(folder, log):
    path = folder / "log.parquet"
    write_parquet(log, path)
    return path


@pytest.mark.parametrize(
    ("cells", "message"),
    [
        ("60.0,9|61.0,4", ("line 3, column run_end: 61.0 differs from run_end 60.0 on line 2, "
         "the same run (0 of proximity); a run has one run_end")),
        ("60.0,9|,4", ("line 3, column run_end: empty differs from run_end 60.0 on line 2, "
         "the same run (0 of proximity); a run has one run_end")),
        ("50.0,9|50.0,4", ("line 2, column run_end: 50.0 is before delivery_time 52.7; "
         "a run ends after its last pickup and delivery")),
        ("30.0,9|30.0,4", ("line 2, column run_end: 30.0 is before pickup_time 37.1; "
         "a run ends after its last pickup and delivery")),
        ("60.0,10|60.0,4", "line 2, column urgency_end: 10 is not an integer in 0-9, or empty"),
        ("60.0,x|60.0,4", "line 2, column urgency_end: 'x' is not an integer"),
        ("abc,9|abc,4", "line 2, column run_end: 'abc' is not a number"),
    ],
)  # fmt: skip
def test_bad_cells_are_named(cells, message):
    first, second = cells.split("|")
    lines = WITH_ENDS.splitlines()
    lines[1] = lines[1].replace("60.0,9", first)
    lines[2] = lines[2].replace("60.0,4", second)
    with pytest.raises(EventLogError) as error:
        parse_carrier_csv("\n".join(lines) + "\n", source="events.csv")
    assert str(error.value) == f"events.csv: {message}"


def test_in_memory_checks_and_the_end_of_a_run_at_its_last_event():
    columns = parse_carrier_csv(GOOD).columns()
    # A run may end exactly at its last delivery.
    log = CarrierLog(**{**columns, "run_end": [52.7, 52.7, 41.5]})
    assert log.run_end.tolist() == [52.7, 52.7, 41.5]
    with pytest.raises(EventLogError, match=r"row 3, column run_end: 41\.0 is before"):
        CarrierLog(**{**columns, "run_end": [60.0, 60.0, 41.0]})
    with pytest.raises(EventLogError, match="row 1, column urgency_end: -2 is not"):
        CarrierLog(**{**columns, "urgency_end": [-2, 1, 1]})
    with pytest.raises(EventLogError, match="column run_end has 2 rows"):
        CarrierLog(**{**columns, "run_end": [60.0, 60.0]})


def test_take_concat_and_sorted_keep_them():
    log = parse_carrier_csv(WITH_ENDS)
    assert log.take([2, 0]).urgency_end.tolist() == [-1, 9]
    both = CarrierLog.concat([log, parse_carrier_csv(GOOD.replace("proximity", "other"))])
    assert both.urgency_end.tolist() == [9, 4, -1, -1, -1, -1]
    with pytest.raises(EventLogError, match="run_end"):
        # The second copy repeats run 0 with another end: refused like any duplicate run.
        CarrierLog.concat(
            [log.take([0]), CarrierLog(**{**log.take([1]).columns(), "run_end": [70.0]})]
        )
    assert log.sorted().run_end[:2].tolist() == [60.0, 60.0]
    assert log != parse_carrier_csv(GOOD)  # the optional columns count for equality
