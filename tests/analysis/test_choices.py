"""Choice statistics from the event table: the double-pursuit rule, candidates, per-run counts."""

from __future__ import annotations

import json

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from swarmtag.analysis import CHOICE_COUNTS, choice_statistics, double_pursuits
from swarmtag.analysis.bootstrap import percentile_interval
from swarmtag.analysis.resampling import condition_generator, iter_multiplicities
from swarmtag.errors import StatisticsError
from swarmtag.io import EventTable
from tests.io.strategies import log_from_rows

NAN = float("nan")
Event = tuple[int, float, str, int, int, float]
"""run, time, kind, carrier, robot, value."""


def table(events: list[Event], *, condition: str = "c", seed: int = 0) -> EventTable:
    return EventTable(
        condition=[condition] * len(events),
        seed=[seed] * len(events),
        run=[e[0] for e in events],
        time=[e[1] for e in events],
        kind=np.array([e[2] for e in events], dtype=str),
        carrier=[e[3] for e in events],
        robot=[e[4] for e in events],
        value=[e[5] for e in events],
        time_unit="tick",
    )


def doubles(events: list[Event]) -> list[bool]:
    t = table(events)
    return double_pursuits(t.run, t.time, t.kind, t.carrier, t.robot).tolist()


def test_k_robots_selecting_one_carrier_in_a_tick_make_k_minus_1_double_pursuits():
    events = [(0, 4.0, "select", 7, robot, 5.0) for robot in (2, 0, 1)]
    assert doubles(events) == [True, False, True]  # robot 0 selects first (time, robot order)
    assert doubles([(0, 4.0, "select", 7, 0, 5.0)]) == [False]


@pytest.mark.parametrize(
    ("end", "double"),
    [("abandon", False), ("timeout", False), ("breakdown", False),  # before the selection phase
     ("lift", True), ("lift_refused", True)],                        # after it: still pursuing
)  # fmt: skip
def test_a_pursuit_ends_before_or_after_the_selections_of_its_tick(end, double):
    events = [
        (0, 1.0, "select", 7, 0, 5.0),
        (0, 5.0, end, 7, 0, 1.0),
        (0, 5.0, "select", 7, 1, 5.0),
    ]
    assert doubles(events) == [False, False, double]
    # One tick later the pursuit is over whatever ended it.
    later = [*events[:2], (0, 6.0, "select", 7, 1, 5.0)]
    assert doubles(later) == [False, False, False]


def test_a_pursuit_lasts_until_the_robots_own_end_or_next_select():
    events = [
        (0, 1.0, "select", 7, 0, 5.0),
        (0, 2.0, "select", 7, 1, 5.0),  # robot 0 pursues 7: double
        (0, 3.0, "timeout", 7, 1, NAN),  # robot 1 gives up ...
        (0, 3.0, "select", 8, 0, 5.0),  # ... and robot 0 switches to carrier 8
        (0, 4.0, "select", 7, 2, 5.0),  # nobody pursues 7 any more
        (0, 4.0, "select", 8, 1, 5.0),  # robot 0 still pursues 8: double
        (0, 5.0, "deliver", 8, 0, 5.0),  # not an end of a pursuit
        (0, 6.0, "select", 8, 0, 5.0),  # robot 0 again: robot 1 still pursues 8
        (0, 7.0, "select", 8, 0, 5.0),  # and still does
        (1, 7.0, "select", 7, 5, 5.0),  # another run, robot 2 of run 0 does not count
    ]
    expected = [False, True, False, False, False, True, False, True, True, False]
    assert doubles(events) == expected
    # Those two are double only because robot 1 still pursues 8; end that first. Then
    # robot 0 re-selecting its own carrier is no double pursuit.
    events.insert(7, (0, 6.0, "abandon", 8, 1, 1.0))
    assert doubles(events) == [*expected[:7], False, False, False, False]


def test_row_order_does_not_matter():
    events = [
        (0, 1.0, "select", 7, 0, 5.0),
        (0, 5.0, "lift", 7, 0, 5.0),
        (0, 5.0, "select", 7, 1, 5.0),
        (0, 5.0, "select", 7, 2, 5.0),
    ]
    order = [3, 1, 2, 0]
    assert doubles([events[i] for i in order]) == [doubles(events)[i] for i in order]


_PHASE = {"breakdown": 0, "abandon": 0, "timeout": 0, "select": 1, "lift": 2, "lift_refused": 2}


def _reference(events: list[Event]) -> list[bool]:
    """The definition, one event at a time: who pursues what, updated in the order of events."""
    kinds = [e for e in range(len(events)) if events[e][2] in _PHASE]
    order = sorted(
        kinds, key=lambda i: (events[i][0], events[i][1], _PHASE[events[i][2]], events[i][4], i)
    )
    pursuing: dict[tuple[int, int], int] = {}
    result = [False] * len(events)
    for i in order:
        run, _, kind, carrier, robot, _ = events[i]
        if kind != "select":
            pursuing.pop((run, robot), None)
            continue
        result[i] = any(
            c == carrier for (r, other), c in pursuing.items() if r == run and other != robot
        )
        pursuing[(run, robot)] = carrier
    return result


events_strategy = st.lists(
    st.tuples(
        st.integers(0, 1),
        st.integers(0, 2).map(float),  # few ticks, carriers and robots: many collisions
        st.sampled_from([*_PHASE, "select", "select", "deliver", "reprioritise"]),
        st.integers(0, 1),
        st.integers(0, 2),
        st.just(5.0),
    ),
    max_size=25,
)


@settings(max_examples=150)
@given(events_strategy)
def test_the_vectorised_rule_is_the_definition(events):
    assert doubles(events) == _reference(events)


def _selection(run: int, time: float, carrier: int, robot: int, among: int) -> list[Event]:
    return [
        (run, time, "select", carrier, robot, 5.0),
        (run, time, "candidates", carrier, robot, float(among)),
    ]


def test_candidates_give_the_shares_and_the_mean():
    events = [
        *_selection(0, 1.0, 1, 0, 1),
        *_selection(0, 1.0, 2, 1, 2),
        *_selection(0, 3.0, 3, 0, 5),  # 3+
        *_selection(1, 2.0, 1, 0, 3),
        (1, 4.0, "select", 2, 1, 5.0),  # no candidates event: not known
        (1, 5.0, "timeout", 2, 1, NAN),
        (0, 6.0, "abandon", 3, 0, 1.0),
        (0, 7.0, "lift_refused", 2, 1, 1.0),
    ]
    (choices,) = choice_statistics(table(events), n_resamples=50)
    assert choices.selections.tolist() == [3, 2]
    assert choices.known.tolist() == [3, 1]
    assert choices.among.tolist() == [[1, 1, 1], [0, 0, 1]]
    assert choices.shares == (0.25, 0.25, 0.5)
    assert choices.mean_candidates == (1 + 2 + 5 + 3) / 4
    np.testing.assert_array_equal(choices.run_shares(), [[1 / 3, 1 / 3, 1 / 3], [0, 0, 1]])
    assert choices.timeouts.tolist() == [0, 1]
    assert choices.abandons.tolist() == [1, 0]
    assert choices.lift_refused.tolist() == [1, 0]
    assert choices.double_pursuits.tolist() == [0, 0]


def test_without_candidates_events_shares_are_unknown_not_zero():
    events = [(0, 1.0, "select", 1, 0, 5.0), (0, 1.0, "select", 1, 1, 5.0)]
    (choices,) = choice_statistics(table(events), n_resamples=20)
    assert choices.shares is None
    assert choices.mean_candidates is None
    assert np.isnan(choices.run_shares()).all()
    entry = choices.to_json()
    assert entry["share_1_candidate"] is None
    assert entry["mean_candidates"] is None
    assert entry["selections"] == 2
    assert entry["selections_with_candidates"] == 0
    assert entry["double_pursuits"] == 1


def test_runs_come_from_the_event_log_and_runs_without_events_count():
    log = log_from_rows([("c", run, 1, 5, 0.0, None) for run in (0, 1, 2, 3)], seed=0)
    events = [
        (0, 1.0, "timeout", 1, 0, NAN),
        (2, 1.0, "timeout", 1, 0, NAN),
        (2, 9.0, "timeout", 1, 1, NAN),
    ]
    (choices,) = choice_statistics(table(events), log=log, n_resamples=400, seed=3)
    assert choices.run_ids.tolist() == [0, 1, 2, 3]
    assert choices.timeouts.tolist() == [1, 0, 2, 0]
    estimate = choices.per_run["timeouts"]
    assert estimate.value == 0.75  # 3 timeouts in 4 runs, not in the 2 runs with events
    # Seeded like the KPIs: the condition's generator, the same resampled runs.
    weights = np.concatenate(
        list(iter_multiplicities(condition_generator(3, "c"), 4, 400, width=4))
    )
    expected = weights @ np.array([1.0, 0.0, 2.0, 0.0]) / 4
    np.testing.assert_allclose(estimate.bootstrap_distribution, expected, rtol=1e-15)
    assert estimate.confidence_interval == percentile_interval(expected)
    (alone,) = choice_statistics(table(events), n_resamples=400, seed=3)
    assert alone.run_ids.tolist() == [0, 2]  # without the log only runs with events are known
    assert alone.per_run["timeouts"].value == 1.5


def test_json_entry_has_every_key():
    events = [*_selection(0, 1.0, 1, 0, 2), *_selection(0, 1.0, 1, 1, 1)]
    (choices,) = choice_statistics(table(events), n_resamples=30)
    entry = json.loads(json.dumps(choices.to_json(), allow_nan=False))
    counts = [key for name in CHOICE_COUNTS for key in (f"{name}_per_run", name)]
    assert list(entry) == [
        "condition", "runs", "selections", "selections_with_candidates", "share_1_candidate",
        "share_2_candidates", "share_3plus_candidates", "mean_candidates", *counts,
    ]  # fmt: skip
    assert entry["share_2_candidates"] == 0.5
    assert entry["double_pursuits_per_run"] == {"value": 1.0, "ci": [1.0, 1.0]}


def test_conditions_follow_the_order_asked():
    events = table([(0, 1.0, "select", 1, 0, 5.0)], condition="b")
    both = EventTable.concat([events, table([(0, 1.0, "select", 1, 0, 5.0)], condition="a")])
    assert [c.condition for c in choice_statistics(both, n_resamples=5)] == ["a", "b"]
    ordered = choice_statistics(both, conditions=["b", "a"], n_resamples=5)
    assert [c.condition for c in ordered] == ["b", "a"]


@pytest.mark.parametrize(
    ("events", "message"),
    [
        ([(0, 1.0, "candidates", 1, 0, 2.0)], (r"row 1 \(c run 0, time 1\.0, robot 0\): a "
         "candidates event without a select of that carrier by that robot")),
        ([(0, 1.0, "select", 1, 0, 5.0), (0, 1.0, "candidates", 2, 0, 2.0)], "row 2 .* without a select"),
        ([(0, 1.0, "select", 1, 0, 5.0), (0, 2.0, "candidates", 1, 0, 2.0)], "row 2 .* without a select"),
        ([(0, 1.0, "select", 1, 0, 5.0), (0, 1.0, "candidates", 1, 0, 0.0)], "value 0.0 is not an integer >= 1"),
        ([(0, 1.0, "select", 1, 0, 5.0), (0, 1.0, "candidates", 1, 0, 1.5)], "value 1.5 is not an integer >= 1"),
        ([(0, 1.0, "select", 1, 0, 5.0), (0, 1.0, "candidates", 1, 0, NAN)], "value nan is not"),
        ([(0, 1.0, "select", -1, 0, 5.0)], "row 1: a select event names no carrier"),
        ([(0, 1.0, "select", 1, 0, 5.0), (0, 2.0, "timeout", 1, -1, NAN)], "row 2: a timeout event names no robot"),
    ],
)  # fmt: skip
def test_inconsistent_tables_are_refused(events, message):
    with pytest.raises(StatisticsError, match=message):
        choice_statistics(table(events), n_resamples=5)


def test_a_table_from_other_runs_than_the_log_is_refused():
    log = log_from_rows([("c", 0, 1, 5, 0.0, None)], seed=4, time_unit="tick")
    with pytest.raises(StatisticsError, match="row 1: run 3 of c is not in the event log"):
        choice_statistics(table([(3, 1.0, "timeout", 1, 0, NAN)], seed=4), log=log)
    with pytest.raises(
        StatisticsError, match="seed 9 of run 0 of c differs from the event log's 4"
    ):
        choice_statistics(table([(0, 1.0, "timeout", 1, 0, NAN)], seed=9), log=log)
    with pytest.raises(StatisticsError, match="condition 'd', which is not among c"):
        choice_statistics(table([(0, 1.0, "timeout", 1, 0, NAN)], condition="d", seed=4), log=log)
    in_seconds = log_from_rows([("c", 0, 1, 5, 0.0, None)], seed=4, time_unit="s")
    with pytest.raises(StatisticsError, match="not from the same runs"):
        choice_statistics(table([(0, 1.0, "timeout", 1, 0, NAN)], seed=4), log=in_seconds)
    with pytest.raises(StatisticsError, match="condition 'x' has no runs in the event log"):
        choice_statistics(table([], seed=4), log=log, conditions=["c", "x"])
