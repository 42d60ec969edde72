"""The warm-up window: which rows stay, every column kept, and the KPIs of the window by hand."""

from __future__ import annotations

import math

import numpy as np
import pytest

from swarmtag.analysis import condition_kpis, run_values, summarize, trim_warmup
from swarmtag.analysis.runs import ConditionRuns
from swarmtag.errors import StatisticsError
from swarmtag.io import CarrierLog
from tests.io.strategies import log_from_rows

# condition, run, carrier, urgency0, order, delivery (None = never); run_end 100 (run 0),
# 80 (run 1). A warm-up of 20 keeps the rows marked *.
#
# run 0        latency / censored value
#   c0 9   0  30
#   c1 2  10  40
#   c2 7  20  50 *   30
#   c3 4  25  35 *   10
#   c4 8  60 never*  100 - 60 = 40
# run 1
#   c0 5   0  10
#   c1 1  30  70 *   40
#   c2 9  50 never*  80 - 50 = 30
ROWS = [
    ("c", 0, 0, 9, 0.0, 30.0),
    ("c", 0, 1, 2, 10.0, 40.0),
    ("c", 0, 2, 7, 20.0, 50.0),
    ("c", 0, 3, 4, 25.0, 35.0),
    ("c", 0, 4, 8, 60.0, None),
    ("c", 1, 0, 5, 0.0, 10.0),
    ("c", 1, 1, 1, 30.0, 70.0),
    ("c", 1, 2, 9, 50.0, None),
]
RUN_END = [100.0] * 5 + [80.0] * 3
URGENCY_END = [9, 3, 8, 5, 9, 6, 4, 9]
KEPT = [2, 3, 4, 6, 7]


def window_log(time_unit: str | None = "s") -> CarrierLog:
    return log_from_rows(ROWS, time_unit=time_unit, run_end=RUN_END, urgency_end=URGENCY_END)


def test_keeps_the_orders_placed_at_or_after_the_warmup_with_every_column():
    log = window_log()
    trimmed = trim_warmup(log, 20.0)
    assert trimmed == log.take(KEPT)
    assert trimmed.time_unit == "s"
    assert trimmed.run_end.tolist() == [100.0, 100.0, 100.0, 80.0, 80.0]
    assert trimmed.urgency_end.tolist() == [8, 5, 9, 4, 9]
    assert trimmed.carrier.tolist() == [2, 3, 4, 1, 2]


def test_kpis_of_the_window_by_hand():
    kpis = condition_kpis(run_values(ConditionRuns.from_log(trim_warmup(window_log(), 20.0), "c")))
    assert kpis.runs == 2
    assert kpis.total_deliveries == 3
    assert kpis.deliveries_per_run == 1.5
    assert kpis.undelivered == 2
    assert kpis.mean_latency == pytest.approx((30 + 10 + 40) / 3)
    # run 0: 2 deliveries between 35 and 50; run 1: a single delivery has no throughput
    assert kpis.throughput == pytest.approx(100 * 2 / 15)
    # censored at run_end: 30, 10, 40 (run 0) and 40, 30 (run 1)
    assert kpis.mean_latency_censored == pytest.approx((30 + 10 + 40 + 40 + 30) / 5)
    # PA ranks the window's orders by their urgency at placement. Run 0 (n = 3): top c4, c2,
    # c3; delivered c3, c2: k = 1 (p <= 30) gives 0, k = 2 (p >= 35) gives 1/2: 2/10.
    # Run 1 (n = 2): k = 1 throughout, top c2, first c1: 0.
    assert kpis.pa == pytest.approx(0.1)


def test_a_warmup_of_zero_trims_nothing_not_even_orders_before_the_run_start():
    log = log_from_rows([("c", 0, 1, 3, -5.0, 10.0), ("c", 0, 2, 3, 4.0, None)])
    assert trim_warmup(log, 0) is log
    assert trim_warmup(log, 0.0) == log


def test_the_window_changes_the_summary():
    log = window_log()
    whole = summarize(log, n_resamples=20).conditions[0].kpis
    window = summarize(trim_warmup(log, 20.0), n_resamples=20).conditions[0].kpis
    assert (whole.total_deliveries, window.total_deliveries) == (6, 3)
    assert whole.mean_latency != window.mean_latency


def test_the_edge_is_inclusive_and_units_are_the_logs():
    log = window_log(time_unit="tick")
    assert trim_warmup(log, 25.0).carrier.tolist() == [3, 4, 1, 2]
    assert trim_warmup(log, 25.0).time_unit == "tick"


def test_an_empty_log_stays_empty():
    empty = window_log().take(np.zeros(len(ROWS), dtype=bool))
    assert len(trim_warmup(empty, 10.0)) == 0


@pytest.mark.parametrize("warmup", [-1.0, math.nan, math.inf, True, "5", None])
def test_a_bad_warmup_is_refused_by_name(warmup):
    with pytest.raises(StatisticsError, match=r"^warmup: .* is not a number >= 0$"):
        trim_warmup(window_log(), warmup)  # type: ignore[arg-type]


def test_a_run_left_without_orders_is_refused_not_dropped():
    with pytest.raises(StatisticsError) as refused:
        trim_warmup(window_log(), 55.0)
    assert str(refused.value) == (
        "warm-up 55: run 1 of c has no order placed at or after it (its latest at 50); "
        "a shorter warm-up keeps every run"
    )
