"""The whole metrics report: baseline choice, condition independence, the JSON contract."""

from __future__ import annotations

import json

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from swarmtag.analysis import CENSORED_METRICS, CORE_METRICS, METRICS, choose_baseline, summarize
from swarmtag.errors import StatisticsError
from swarmtag.io import CarrierLog
from tests.io.strategies import carrier_logs, log_from_rows, permuted


def _log(names, runs=6, seed=0) -> CarrierLog:
    rng = np.random.default_rng(seed)
    rows = []
    for name in names:
        for run in range(runs):
            for carrier in range(5):
                delivery = float(rng.integers(1, 100)) if rng.random() < 0.9 else None
                rows.append(
                    (name, run, carrier, int(rng.integers(0, 10)), -1.0 * carrier, delivery)
                )
    return log_from_rows(rows, time_unit="tick")


def test_baseline_choice():
    assert choose_baseline(["urgency:alpha=0.7", "proximity"]) == "proximity"
    assert choose_baseline(["weighted:w=0.5", "weighted:w=0.1"]) == "weighted:w=0.1"
    assert choose_baseline(["a", "b"], "b") == "b"


def test_unknown_baseline_names_the_conditions():
    with pytest.raises(StatisticsError) as error:
        choose_baseline(["urgency:alpha=0.7", "proximity"], "random")
    assert str(error.value) == (
        "unknown baseline 'random'; the log has conditions proximity, urgency:alpha=0.7"
    )


def test_empty_log_is_refused():
    with pytest.raises(StatisticsError, match="no rows"):
        summarize(log_from_rows([]))


def test_json_has_exactly_the_contract_shape():
    report = summarize(
        _log(["urgency:alpha=0.7", "proximity", "urgency:alpha=3.0"]), n_resamples=50
    )
    document = json.loads(json.dumps(report.to_json(), allow_nan=False))
    assert list(document) == ["conditions", "comparisons"]
    assert [c["condition"] for c in document["conditions"]] == [
        "proximity",
        "urgency:alpha=0.7",
        "urgency:alpha=3.0",
    ]
    for entry in document["conditions"]:
        # SPEC §8.2's keys in its order, then the extensions (no urgency_end: no PA at delivery).
        assert list(entry) == [
            "condition",
            "runs",
            *CORE_METRICS,
            "total_deliveries",
            "undelivered",
            *CENSORED_METRICS,
            "runs_without_run_end",
        ]
        assert entry["runs_without_run_end"] == 6
        assert entry["runs"] == 6
        for metric in METRICS:
            assert list(entry[metric]) == ["value", "ci"]
            if metric == "km_p95_latency" and entry[metric]["value"] is None:
                assert entry[metric]["ci"] == [None, None]  # the KM curve stays below 0.95
                continue
            assert isinstance(entry[metric]["value"], float)
            low, high = entry[metric]["ci"]
            assert low <= high
        assert isinstance(entry["total_deliveries"], int)
        assert entry["total_deliveries"] + entry["undelivered"] == 30
    pairs = [(c["condition"], c["metric"]) for c in document["comparisons"]]
    assert pairs == [
        (name, metric) for name in ("urgency:alpha=0.7", "urgency:alpha=3.0") for metric in METRICS
    ]
    for comparison in document["comparisons"]:
        assert list(comparison) == [
            "condition",
            "baseline",
            "metric",
            "diff",
            "ci",
            "p_bootstrap",
            "p_mannwhitney",
            "undelivered_differs",
            "underpowered",
            "smallest_p_mannwhitney",
        ]
        assert comparison["baseline"] == "proximity"
        assert isinstance(comparison["undelivered_differs"], bool)
        if comparison["metric"] == "km_p95_latency":
            assert comparison["p_mannwhitney"] is None  # no per-run value
            if comparison["diff"] is None:  # a KM curve stays below 0.95: nothing to compare
                assert comparison["p_bootstrap"] is None
                continue
        else:
            assert 0 <= comparison["p_mannwhitney"] <= 1
        assert 0 <= comparison["p_bootstrap"] <= 1


def test_json_has_null_where_undefined():
    rows = [("proximity", 0, 1, 5, 0.0, 10.0), ("proximity", 1, 1, 5, 0.0, 12.0)]
    rows += [("urgency:alpha=0.7", 0, 1, 5, 0.0, None)]
    document = summarize(log_from_rows(rows), n_resamples=20).to_json()
    proximity, urgency = document["conditions"]
    assert proximity["throughput"] == {"value": None, "ci": [None, None]}  # one delivery per run
    assert urgency["p95_latency"] == {"value": None, "ci": [None, None]}
    assert urgency["undelivered"] == 1
    assert "null" in json.dumps(document, allow_nan=False)


def test_results_do_not_depend_on_which_conditions_are_present():
    both = summarize(_log(["proximity", "urgency:alpha=0.7"]), n_resamples=200, seed=5)
    more = summarize(
        _log(["proximity", "urgency:alpha=0.7", "weighted:w=0.5"]).take(
            np.arange(60)
        ),  # the first two conditions' rows only: identical data
        n_resamples=200,
        seed=5,
    )
    three = summarize(
        _log(["proximity", "urgency:alpha=0.7", "urgency:alpha=9.0"]), n_resamples=200, seed=5
    )
    assert more.to_json() == both.to_json()
    for name in ("proximity", "urgency:alpha=0.7"):
        for metric in METRICS:
            np.testing.assert_array_equal(
                both.condition(name).estimate(metric).bootstrap_distribution,
                three.condition(name).estimate(metric).bootstrap_distribution,
            )


@settings(max_examples=30)
@given(carrier_logs(), st.integers(0, 2**32 - 1))
def test_permuting_rows_changes_no_figure_and_no_interval(log, seed):
    first = summarize(log, n_resamples=40, seed=3).to_json()
    assert summarize(permuted(log, seed), n_resamples=40, seed=3).to_json() == first


def test_report_keeps_its_settings():
    report = summarize(_log(["a", "b"]), baseline="b", n_resamples=30, seed=9)
    assert (report.baseline, report.n_resamples, report.seed, report.time_unit) == (
        "b",
        30,
        9,
        "tick",
    )
    assert [s.condition for s in report.conditions] == ["b", "a"]
    with pytest.raises(StatisticsError, match="no condition"):
        report.condition("c")


def test_the_report_is_the_same_on_one_thread_and_on_several(monkeypatch):
    log = _log(["proximity", "urgency:alpha=0.7", "urgency:alpha=3.0", "weighted:w=0.5"])
    reports = []
    for threads in ("1", "3"):
        monkeypatch.setenv("SWARMTAG_THREADS", threads)
        reports.append(summarize(log, n_resamples=500, seed=4))
    one, several = reports
    assert json.dumps(one.to_json()) == json.dumps(several.to_json())
    for first, second in zip(one.conditions, several.conditions, strict=True):
        for metric in METRICS:
            assert (
                first.estimate(metric).bootstrap_distribution.tobytes()
                == second.estimate(metric).bootstrap_distribution.tobytes()
            )
