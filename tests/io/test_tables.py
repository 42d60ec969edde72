"""The in-memory tables: conversion, checks with row and column in messages, immutability."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from swarmtag.errors import EventLogError
from swarmtag.io import MISSING_ID, CarrierLog, EventTable

NAN = float("nan")


def _columns(**changes):
    columns = {
        "condition": ["proximity", "proximity", "urgency:alpha=0.7"],
        "run": [0, 0, 0],
        "seed": [7, 7, 7],
        "carrier": [1, 2, 1],
        "urgency0": [9, 0, 4],
        "order_time": [-240.0, 0.0, -106.7],
        "pickup_time": [10.0, NAN, 12.5],
        "delivery_time": [25.5, NAN, 30.0],
        "robot": [2, -1, 0],
    }
    columns.update(changes)
    return columns


def test_columns_become_typed_read_only_arrays():
    log = CarrierLog(**_columns(), time_unit="s")
    assert log.run.dtype == np.int64
    assert log.order_time.dtype == np.float64
    assert log.condition.dtype.kind == "U"
    assert log.robot.tolist() == [2, MISSING_ID, 0]
    assert len(log) == 3
    assert log.conditions == ("proximity", "urgency:alpha=0.7")
    with pytest.raises(ValueError, match="read-only"):
        log.run[0] = 5
    with pytest.raises(dataclasses.FrozenInstanceError):
        log.time_unit = "tick"  # type: ignore[misc]


def test_the_caller_keeps_a_writable_array():
    run = np.array([0, 0, 0])
    CarrierLog(**_columns(run=run))
    run[0] = 1  # not frozen behind the caller's back


def test_integral_floats_are_accepted_as_integers_and_nan_as_no_robot():
    log = CarrierLog(**_columns(run=[0.0, 0.0, 0.0], robot=[2.0, NAN, 0.0]))
    assert log.run.dtype == np.int64
    assert log.robot.tolist() == [2, -1, 0]


@pytest.mark.parametrize(
    ("changes", "message"),
    [
        ({"urgency0": [9, 10, 4]}, "row 2, column urgency0: 10 is not an integer in 0-9"),
        ({"run": [0, -1, 0]}, "row 2, column run: -1 is not an integer >= 0"),
        ({"run": [0, 0.5, 0]}, "row 2, column run: 0.5 is not an integer >= 0"),
        ({"carrier": [1, NAN, 1]}, "row 2, column carrier: nan is not an integer >= 0"),
        ({"robot": [2, -3, 0]}, "row 2, column robot: -3 is not an integer >= 0, or empty"),
        ({"order_time": [-1.0, NAN, 0.0]}, "row 2, column order_time: nan is not a finite number"),
        (
            {"delivery_time": [np.inf, NAN, 30.0]},
            "row 1, column delivery_time: inf is not a finite",
        ),
        ({"condition": ["proximity", "", "x"]}, "row 2, column condition: is empty; expected text"),
        ({"condition": ["proximity", " x", "x"]}, "row 2, column condition: ' x' has white space"),
        ({"condition": ["proximity", 3, "x"]}, "row 2, column condition: 3 is not text"),
        ({"run": ["0", "0", "0"]}, "column run holds <U1; expected an integer per row"),
        ({"order_time": [True, False, True]}, "column order_time holds bool"),
        ({"seed": [7, 7]}, "column seed has 2 rows but column condition has 3"),
        ({"run": [[0], [0], [0]]}, "column run has shape (3, 1); expected one value per row"),
    ],
)
def test_bad_columns_name_row_and_column(changes, message):
    with pytest.raises(EventLogError) as error:
        CarrierLog(**_columns(**changes))
    assert str(error.value).startswith(message)


def test_delivery_needs_pickup_before_it_and_a_robot():
    with pytest.raises(EventLogError, match=r"row 1, column pickup_time: is empty but delivery"):
        CarrierLog(**_columns(pickup_time=[NAN, NAN, 12.5]))
    with pytest.raises(EventLogError, match=r"row 3, column delivery_time: 30.0 is before pickup"):
        CarrierLog(**_columns(pickup_time=[10.0, NAN, 31.0]))
    with pytest.raises(EventLogError, match=r"row 1, column robot: is empty but the carrier was"):
        CarrierLog(**_columns(robot=[-1, -1, 0]))
    # Picked up but never delivered (a breakdown) is fine, with or without a robot.
    CarrierLog(**_columns(pickup_time=[10.0, 3.0, 12.5], robot=[2, 1, 0]))


def test_duplicate_carrier_in_a_run_is_named():
    columns = _columns(carrier=[5, 5, 1])
    with pytest.raises(EventLogError) as error:
        CarrierLog(**columns)
    assert str(error.value) == "run 0 of proximity has two rows for carrier 5 (rows 1 and 2)"
    # The same carrier in another run or another condition is fine.
    CarrierLog(**_columns(carrier=[5, 5, 5], run=[0, 1, 0]))


def test_three_rows_for_one_carrier():
    columns = {name: [*values, values[0]] for name, values in _columns(carrier=[5, 5, 1]).items()}
    with pytest.raises(EventLogError, match=r"has 3 rows for carrier 5 \(rows 1, 2 and 4\)"):
        CarrierLog(**columns)


def test_a_run_has_one_seed():
    with pytest.raises(EventLogError) as error:
        CarrierLog(**_columns(seed=[7, 8, 7]))
    assert str(error.value) == (
        "row 2, column seed: 8 differs from seed 7 on row 1, the same run (0 of proximity); "
        "a run has one seed"
    )


def test_time_unit_is_tick_or_seconds():
    with pytest.raises(EventLogError, match="time unit 'min'"):
        CarrierLog(**_columns(), time_unit="min")


def test_equality_take_and_sorted():
    log = CarrierLog(**_columns())
    assert log == CarrierLog(**_columns())  # NaN equals NaN here: same table
    assert log != CarrierLog(**_columns(), time_unit="s")
    assert log != CarrierLog(**_columns(order_time=[-240.0, 0.0, -106.6]))
    reordered = log.take([2, 1, 0])
    assert reordered != log
    assert reordered.sorted() == log
    assert log.take([True, False, True]).carrier.tolist() == [1, 1]
    assert repr(log) == (
        "CarrierLog(rows=3, conditions=('proximity', 'urgency:alpha=0.7'), time_unit=None)"
    )


def test_empty_log():
    empty = CarrierLog(**{name: [] for name in _columns()})
    assert len(empty) == 0
    assert empty.conditions == ()


def test_event_table():
    table = EventTable(
        condition=["proximity", "proximity"],
        seed=[0, 0],
        run=[3, 3],
        time=[12.0, 40.0],
        kind=["select", "reprioritise"],
        carrier=[5, 5],
        robot=[1, -1],
        value=[NAN, 9.0],
        time_unit="tick",
    )
    assert table.robot.tolist() == [1, MISSING_ID]
    assert np.isnan(table.value[0])
    with pytest.raises(EventLogError, match="row 2, column kind: is empty"):
        EventTable(**{**table.columns(), "kind": ["select", ""]})
    with pytest.raises(EventLogError, match="row 1, column time: nan is not a finite number"):
        EventTable(**{**table.columns(), "time": [NAN, 1.0]})


def test_concat_keeps_rows_in_order_and_requires_one_time_unit():
    from swarmtag.errors import EventLogError
    from swarmtag.io import CarrierLog

    def one(condition, unit):
        return CarrierLog(
            condition=[condition], run=[0], seed=[0], carrier=[1], urgency0=[3],
            order_time=[-2.0], pickup_time=[1.0], delivery_time=[4.0], robot=[0], time_unit=unit,
        )  # fmt: skip

    joined = CarrierLog.concat([one("proximity", "tick"), one("urgency:alpha=0.7", "tick")])
    assert joined.condition.tolist() == ["proximity", "urgency:alpha=0.7"]
    assert joined.time_unit == "tick"
    with pytest.raises(EventLogError, match="different time units"):
        CarrierLog.concat([one("a", "tick"), one("b", "s")])
    with pytest.raises(EventLogError, match="empty"):
        CarrierLog.concat([])
