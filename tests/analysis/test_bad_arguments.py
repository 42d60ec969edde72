"""The public statistics functions refuse nonsense with ``StatisticsError`` (issue 35, item 7)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from swarmtag.analysis import (
    ConditionRuns,
    alignment_k,
    bootstrap_p_value,
    censored_latencies,
    choose_baseline,
    condition_seed_sequence,
    condition_statistics,
    km_quantile,
    latency_by_urgency,
    mann_whitney_p,
    percentile_interval,
    priority_alignment,
    run_values,
    summarize,
)
from swarmtag.data import example_trial_path
from swarmtag.errors import StatisticsError
from swarmtag.io import read_event_log

LOG = read_event_log(example_trial_path())
RUNS = ConditionRuns.from_log(LOG, "proximity")


@pytest.mark.parametrize("level", [-1, 0, 1, 1.5, math.nan, math.inf, "0.95", None, True])
def test_percentile_interval_refuses_a_level_outside_zero_one(level):
    with pytest.raises(StatisticsError, match="confidence_level"):
        percentile_interval([1.0, 2.0, 3.0], confidence_level=level)


@pytest.mark.parametrize(
    "replicates", [["x"], [[1.0, 2.0]], [math.inf, 1.0], [1e308, -1e308], "abc", object()]
)
def test_percentile_interval_refuses_replicates_it_cannot_order(replicates):
    with pytest.raises(StatisticsError, match="replicates"):
        percentile_interval(replicates)


@pytest.mark.parametrize("q", [-5, 100.5, math.nan, math.inf, None, "95", 10**400])
def test_km_quantile_refuses_a_percentile_outside_0_100(q):
    with pytest.raises(StatisticsError, match="q: "):
        km_quantile(censored_latencies(RUNS), q)


@pytest.mark.parametrize(
    "call",
    [
        lambda: km_quantile(1.5),
        lambda: censored_latencies(None),
        lambda: run_values(RUNS, curve_thresholds=5),
        lambda: condition_statistics(RUNS, n_resamples=5, curve_percentiles=50.0),
        lambda: condition_statistics("proximity", n_resamples=5),
        lambda: condition_statistics(RUNS, n_resamples=5, compiled="yes"),
        lambda: summarize(LOG, n_resamples=5, baseline=np.array([])),
        lambda: summarize(LOG.carrier, n_resamples=5),
        lambda: choose_baseline(5),
        lambda: alignment_k(5, [math.nan]),
        lambda: alignment_k(5, [-1]),
        lambda: alignment_k(10**5000, [3]),
        lambda: bootstrap_p_value(["x"]),
        lambda: mann_whitney_p([object()], [1.0]),
        lambda: condition_seed_sequence(-1, "c"),
        lambda: condition_seed_sequence(0, 7),
        lambda: latency_by_urgency(RUNS, levels=3),
        lambda: latency_by_urgency(RUNS, levels=[10]),
        lambda: priority_alignment(RUNS, thresholds=[5.5]),
        lambda: priority_alignment(RUNS, urgency=[1, 2]),
    ],
)
def test_wrong_kinds_and_values_are_statistics_errors(call):
    with pytest.raises(StatisticsError):
        call()


def test_valid_calls_still_answer():
    assert percentile_interval(np.arange(101.0)).low == 2.5
    assert km_quantile(censored_latencies(RUNS), 0) is not None
    assert mann_whitney_p(None, [1.0]) is None  # a metric without per-run values
