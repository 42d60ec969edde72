"""Rows the terminal leaves out because they repeat others, and the note that names them."""

from __future__ import annotations

import pytest

from swarmtag.analysis import CENSORED_METRICS, summarize
from swarmtag.analysis.repeats import shown_rows, zero_cell, zero_rows
from swarmtag.data import example_trial
from swarmtag.io import CarrierLog, parse_carrier_csv
from tests.analysis.test_headline import _log

NAN = float("nan")


def test_everything_delivered_leaves_out_the_censored_rows_and_the_zero_differences():
    report = summarize(_log(12), n_resamples=300, seed=1)
    assert all(c.kpis.undelivered == 0 for c in report.conditions)
    for statistics in report.conditions:  # what "repeat" means: the same figures
        kpis = statistics.kpis
        assert kpis.p95_latency_censored == kpis.p95_latency
        assert kpis.mean_latency_censored == kpis.mean_latency
    deliveries = next(k for k in report.comparisons if k.metric == "deliveries_per_run")
    interval = deliveries.confidence_interval
    assert (deliveries.diff, interval.low, interval.high) == (0, 0, 0)
    shown = shown_rows(report)
    assert shown.values == (
        "p95_latency", "mean_latency", "throughput", "pa", "deliveries_per_run",
        "total_deliveries",
    )  # fmt: skip
    assert shown.differences == ("p95_latency", "mean_latency", "throughput", "pa")
    assert shown.runs_each == 12
    assert shown.note == (
        "Left out: the censored latencies, KM P95 and the undelivered counts (every carrier "
        "was delivered: nothing is censored, so they repeat the delivered-only rows). "
        "Left out as 0 [0, 0] for every condition: the differences in Deliveries per run."
    )


def test_undelivered_carriers_keep_every_row():
    report = summarize(parse_carrier_csv(example_trial().read_text()), n_resamples=300)
    shown = shown_rows(report)
    assert set(CENSORED_METRICS) <= set(shown.values)
    assert "undelivered" in shown.values
    assert set(CENSORED_METRICS) <= set(shown.differences)
    assert shown.note is None
    assert shown.runs_each == 12


def test_rows_zero_in_every_condition_are_left_out_with_their_differences():
    count = 2 * 10 * 2  # two conditions, ten runs, two carriers, nothing delivered
    log = CarrierLog(
        condition=["proximity"] * 20 + ["urgency:alpha=0.7"] * 20,
        run=[run for _ in range(2) for run in range(10) for _ in range(2)],
        seed=[0] * count,
        carrier=[1, 2] * 20,
        urgency0=[1, 9] * 20,
        order_time=[0.0] * count,
        pickup_time=[NAN] * count,
        delivery_time=[NAN] * count,
        robot=[-1] * count,
    )
    report = summarize(log, n_resamples=100)
    assert report.condition("proximity").pa.value == 0
    shown = shown_rows(report)
    assert "pa" not in shown.values
    assert "pa" not in shown.differences
    assert "undelivered" in shown.values  # 20 each: not zero
    assert shown.note is not None
    assert shown.note.startswith(
        "Left out as 0 [0, 0] in every condition (differences too): PA (5-50 %); "
        "Deliveries per run; Total deliveries"
    )


def test_different_run_counts_keep_the_runs_row():
    log = _log(12)
    fewer = log.take((log.condition == "proximity") | (log.run < 11))
    assert shown_rows(summarize(fewer, n_resamples=100)).runs_each is None


@pytest.mark.parametrize(
    ("cell", "zero"),
    [("0", True), ("0 [0, 0]", True), ("0.0500 [0, 0.1500]", False), ("n/a", False),
     ("unknown", False), ("-0 [0, 0]", True), ("12", False), ("0 ‡", False)],
)  # fmt: skip
def test_zero_cell(cell, zero):
    assert zero_cell(cell) is zero


def test_zero_rows_keeps_order_and_names_the_rest():
    rows = [["Runs", "20", "20"], ["Refused lifts", "0", "0"], ["Timeouts", "1", "0"]]
    kept, dropped = zero_rows(rows)
    assert kept == [["Runs", "20", "20"], ["Timeouts", "1", "0"]]
    assert dropped == ["Refused lifts"]
