"""The rules that turn trial marks and tag changes into an event log (pure: no bag needed)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from swarmtag.errors import BagError
from swarmtag.io.bag_trials import (
    END_OF_TIME,
    RobotEvents,
    TagChanges,
    TrialMark,
    carrier_log,
    event_table,
    tick_nanoseconds,
    trial_time,
    trials,
)

S = 10**9
IDLE, AWAITING, PICKED_UP = 0, 1, 2


def start(at: int = 0, **fields) -> TrialMark:
    return TrialMark(time=at, starts=True, where=f"start at {at}", **{"condition": "c", **fields})


def end(at: int) -> TrialMark:
    return TrialMark(time=at, starts=False, where=f"end at {at}")


def changes(*rows: tuple[int, int, int, int, int]) -> TagChanges:
    """(time ns, marker, status, urgency, robot) rows, in bag order."""
    columns = (
        [np.array(c, dtype=np.int64) for c in zip(*rows, strict=True)]
        if rows
        else [np.zeros(0, dtype=np.int64)] * 5
    )
    return TagChanges(
        time=columns[0], marker=columns[1], status=columns[2], urgency=columns[3], robot=columns[4]
    )


def one(marks, rows):
    return carrier_log(trials(marks, source="bag"), changes(*rows), source="bag", bag_start=0)


def test_seconds_and_ticks_are_exact():
    assert trial_time(12_500_000_000, "s", 0.0) == 12.5
    assert trial_time(-40 * S, "s", 0.0) == -40.0
    for tick in (0.1, 0.05, 0.2, 0.123456):
        step = tick_nanoseconds(tick)
        for n in (0, 1, 3, 37, 2999, 10**6):
            assert trial_time(n * step, "tick", tick) == float(n)
            assert trial_time(n * step, "s", tick) == np.float64(n) * tick  # the simulator's times
    assert tick_nanoseconds(0.1) == 100_000_000


def test_trial_windows_from_start_and_end_marks():
    found = trials([start(10), end(20), start(30), start(50)], source="bag")
    assert [(t.start, t.until, t.end) for t in found] == [
        (10, 20, 20),
        (30, 49, None),
        (50, END_OF_TIME, None),
    ]


@pytest.mark.parametrize(
    ("marks", "message"),
    [
        ([end(5), start(10)], "bag: end at 5 ends a trial, but none was started before it"),
        ([], "bag: no trial starts in the bag; nothing to import"),
        ([start(0, time_unit="tick")], "bag: start at 0: times are in ticks but tick is 0.0"),
        ([start(0, time_unit="min")], "bag: start at 0: time_unit 'min' is not 's' or 'tick'"),
        ([start(0, tick=math.inf)], "bag: start at 0: tick inf is not a number of seconds >= 0"),
        (
            [start(0, markers=(1, 1), urgency0=(1, 1), order_time=(0.0, 0.0))],
            "bag: start at 0: markers lists a carrier twice",
        ),
        (
            [start(0, markers=(1,), urgency0=(1, 2), order_time=(0.0,))],
            "bag: start at 0: markers, urgency0 and order_time have different lengths",
        ),
    ],
)
def test_marks_that_give_no_trials_are_refused(marks, message):
    with pytest.raises(BagError) as error:
        trials(marks, source="bag")
    assert str(error.value).startswith(message)


def test_the_order_is_the_last_change_to_awaiting_pickup_at_or_before_the_start():
    log = one(
        [start(100 * S), end(200 * S)],
        [
            (10 * S, 1, AWAITING, 2, -1),  # an old order, delivered in an earlier trial
            (20 * S, 1, PICKED_UP, 2, 0),
            (30 * S, 1, IDLE, 2, 0),
            (60 * S, 1, AWAITING, 6, -1),  # this trial's order: -40 s
            (70 * S, 1, AWAITING, 8, -1),  # urgency changes keep the order time
            (100 * S, 2, AWAITING, 3, -1),  # at the start exactly: time 0
            (130 * S, 3, IDLE, 1, -1),  # never awaiting: not in the trial
        ],
    )
    assert log.carrier.tolist() == [1, 2]
    assert log.order_time.tolist() == [-40.0, 0.0]
    assert log.urgency0.tolist() == [8, 3]  # the urgency at the start
    assert log.run_end.tolist() == [100.0, 100.0]


def test_a_carrier_ordered_during_the_trial_has_its_urgency_when_ordered():
    log = one(
        [start(0)], [(0, 5, IDLE, 1, -1), (7 * S, 5, AWAITING, 4, -1), (9 * S, 5, AWAITING, 9, -1)]
    )
    assert (log.order_time.tolist(), log.urgency0.tolist(), log.urgency_end.tolist()) == (
        [7.0],
        [4],
        [9],
    )
    assert math.isnan(log.run_end[0])


def test_only_a_robot_delivers_and_the_pickup_is_the_lift_before_it():
    log = one(
        [start(0), end(100 * S)],
        [
            (0, 1, AWAITING, 5, -1),
            (10 * S, 1, PICKED_UP, 5, 0),
            (20 * S, 1, IDLE, 5, -1),  # an operator put it down: returned, not delivered
            (30 * S, 1, AWAITING, 5, -1),
            (40 * S, 1, PICKED_UP, 5, 2),
            (50 * S, 1, PICKED_UP, 6, -1),  # its urgency grows while carried
            (60 * S, 1, IDLE, 6, 2),  # delivered by robot 2
            (70 * S, 1, AWAITING, 9, -1),  # after its delivery: ignored
        ],
    )
    assert (log.pickup_time[0], log.delivery_time[0], log.robot[0], log.urgency_end[0]) == (
        40.0,
        60.0,
        2,
        6,
    )


def test_a_carrier_still_carried_at_the_end_has_a_pickup_and_no_delivery():
    log = one(
        [start(0), end(30 * S)],
        [(0, 1, AWAITING, 5, -1), (10 * S, 1, PICKED_UP, 5, 1), (40 * S, 1, IDLE, 5, 1)],
    )
    assert log.pickup_time[0] == 10.0
    assert math.isnan(log.delivery_time[0])
    assert log.robot[0] == -1


def test_changes_at_one_instant_keep_the_bag_order():
    rows = [(0, 1, AWAITING, 5, -1), (10 * S, 1, PICKED_UP, 5, 1), (10 * S, 1, PICKED_UP, 8, -1)]
    assert one([start(0)], rows).urgency_end.tolist() == [8]
    assert one([start(0)], [rows[0], rows[2], rows[1]]).urgency_end.tolist() == [5]


def test_a_listed_carrier_takes_urgency_and_order_from_the_list():
    log = one(
        [start(0, markers=(9, 4), urgency0=(1, 2), order_time=(-3.5, 0.0))],
        [(0, 4, AWAITING, 7, -1), (5 * S, 4, PICKED_UP, 7, 0), (6 * S, 11, AWAITING, 3, -1)],
    )
    assert log.carrier.tolist() == [9, 4]  # in the list's order; 11 is not listed
    assert log.urgency0.tolist() == [1, 2]
    assert log.order_time.tolist() == [-3.5, 0.0]
    assert log.urgency_end.tolist() == [1, 7]  # no change: its listed urgency


def test_stories_an_event_log_cannot_tell_are_refused():
    with pytest.raises(BagError, match="carrier 1 is lifted without an order"):
        one([start(0)], [(5 * S, 1, PICKED_UP, 5, 0)])
    with pytest.raises(
        BagError,
        match=r"carrier 1 is delivered 5\.000 s after the start but was lifted before the trial started",
    ):
        one(
            [start(0, markers=(1,), urgency0=(1,), order_time=(-9.0,))],
            [(-S, 1, PICKED_UP, 5, 0), (5 * S, 1, IDLE, 5, 0)],
        )
    with pytest.raises(
        BagError, match=r"repeats run 0 of c \(it started 0.000 s into the bag too\)"
    ):
        one([start(0), start(10 * S)], [(0, 1, AWAITING, 5, -1)])
    with pytest.raises(
        BagError, match=r"has times in 'tick' but .* in 's'; a log has one time unit"
    ):
        one([start(0), start(10 * S, run=1, time_unit="tick", tick=0.1)], [(0, 1, AWAITING, 5, -1)])


def test_events_belong_to_the_trial_they_happen_in_sorted_stably_by_time():
    found = trials([start(10 * S, seed=3), end(20 * S), start(30 * S, run=1, seed=3)], source="bag")
    events = RobotEvents(
        time=np.array([5, 15, 12, 12, 25, 31], dtype=np.int64) * S,
        kind=["select", "lift", "select", "candidates", "gap", "deliver"],
        robot=np.array([0, 1, 1, 1, 0, -1], dtype=np.int64),
        carrier=np.array([1, 2, 2, 2, 3, -1], dtype=np.int64),
        value=np.array([1.0, 2.0, 3.0, 4.0, 5.0, math.nan]),
    )
    table = event_table(found, events, source="bag", bag_start=0)
    assert table.kind.tolist() == ["select", "candidates", "lift", "deliver"]
    assert table.time.tolist() == [2.0, 2.0, 5.0, 1.0]
    assert table.run.tolist() == [0, 0, 0, 1]
    assert table.robot.tolist() == [1, 1, 1, -1]
    assert table.time_unit == "s"
