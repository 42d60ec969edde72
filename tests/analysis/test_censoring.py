"""Censoring-aware latency, the Kaplan-Meier P95 and PA at delivery, against hand computations."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy import stats

from swarmtag.analysis import (
    ConditionRuns,
    _kernels,
    censored_latencies,
    condition_kpis,
    condition_statistics,
    km_quantile,
    run_ends,
    run_values,
    summarize,
)
from swarmtag.analysis._kernels import numba_available, rank_targets
from swarmtag.analysis.censoring import km_resampled_quantiles
from swarmtag.analysis.resampling import condition_generator, iter_multiplicities, multiplicities
from tests.io.strategies import carrier_logs, log_from_rows

needs_numba = pytest.mark.skipif(not numba_available(), reason="numba (the fast extra) is absent")
ENGINES = [pytest.param(False, id="numpy"), pytest.param(True, id="compiled", marks=needs_numba)]
"""Both implementations of the kernels: they must give the same bits."""

# condition, run, carrier, urgency0, order, delivery (None = never); pickups 1 before delivery.
#
# run 0, run_end 40      latency / censored value
#   c1 9 -10 12             22
#   c2 7  -6 30             36
#   c3 7  -8 20             28
#   c4 2  -2 20             22
#   c5 0   0 never          40 - 0 = 40
# run 1, run_end 25
#   c1 5  -4 10             14
#   c2 8  -9 never          25 + 9 = 34
#   c3 1   0 never          25
# run 2, no run_end: ends at its latest pickup or delivery, 15
#   c1 3  -1 15             16
#   c2 3  -3 never          15 + 3 = 18
# run 3, no run_end and nothing recorded: ends at 0
#   c1 4  -5 never          0 + 5 = 5
ROWS = [
    ("c", 0, 1, 9, -10.0, 12.0),
    ("c", 0, 2, 7, -6.0, 30.0),
    ("c", 0, 3, 7, -8.0, 20.0),
    ("c", 0, 4, 2, -2.0, 20.0),
    ("c", 0, 5, 0, 0.0, None),
    ("c", 1, 1, 5, -4.0, 10.0),
    ("c", 1, 2, 8, -9.0, None),
    ("c", 1, 3, 1, 0.0, None),
    ("c", 2, 1, 3, -1.0, 15.0),
    ("c", 2, 2, 3, -3.0, None),
    ("c", 3, 1, 4, -5.0, None),
]
RUN_END = [40.0] * 5 + [25.0] * 3 + [None] * 3


@pytest.fixture
def runs() -> ConditionRuns:
    return ConditionRuns.from_log(log_from_rows(ROWS, run_end=RUN_END), "c")


def test_run_ends_and_their_fallback(runs):
    ends, recorded = run_ends(runs)
    assert ends.tolist() == [40.0, 25.0, 15.0, 0.0]
    assert recorded.tolist() == [True, True, False, False]


def test_censored_values_mean_and_p95(runs):
    latencies = censored_latencies(runs)
    assert latencies.values.tolist() == [5, 14, 16, 18, 22, 22, 25, 28, 34, 36, 40]
    assert latencies.observed.tolist() == [0, 1, 1, 0, 1, 1, 0, 1, 0, 1, 0]
    assert latencies.per_run.tolist() == [5, 3, 2, 1]
    kpis = condition_kpis(run_values(runs))
    assert kpis.mean_latency_censored == pytest.approx(260 / 11, rel=1e-15)
    # Position 0.95 * (11 - 1) = 9.5: 36 + 0.5 * (40 - 36) = 38.
    assert kpis.p95_latency_censored == 38.0
    # Delivered only: 14, 16, 22, 22, 28, 36 -> mean 23, P95 at 4.75: 28 + 0.75 * 8 = 34.
    assert (kpis.mean_latency, kpis.p95_latency) == (23.0, 34.0)
    assert kpis.runs_without_run_end == 2
    values = run_values(runs)
    assert values.mean_latency_censored.tolist() == [148 / 5, 73 / 3, 17.0, 5.0]
    # Run 0: 22, 22, 28, 36, 40 -> position 3.8: 36 + 0.8 * 4 = 39.2.
    assert values.p95_latency_censored[0] == pytest.approx(39.2, rel=1e-15)
    assert values.per_run("km_p95_latency") is None


def test_kaplan_meier_by_hand(runs):
    latencies = censored_latencies(runs)
    # At risk and deliveries: 14 (10, 1), 16 (9, 1), 22 (7, 2), 28 (4, 1), 36 (2, 1); the
    # CDF climbs 1/10, 2/10, 3/7, 4/7, 11/14 = 0.786 and never reaches 0.95.
    assert km_quantile(latencies, 95) is None
    assert km_quantile(latencies, 50) == 28.0  # 3/7 < 0.5 <= 4/7
    assert km_quantile(latencies, 20) == 16.0  # exactly 2/10
    statistics = condition_statistics(runs, n_resamples=200, seed=1)
    assert statistics.km_p95_latency.value is None
    assert statistics.km_p95_latency.n_undefined == 200  # undefined outright: no interval
    assert statistics.km_p95_latency.confidence_interval.low is None


@pytest.mark.parametrize("compiled", ENGINES)
def test_kaplan_meier_is_scipys(compiled):
    rng = np.random.default_rng(7)
    values = rng.integers(0, 40, 300).astype(float)  # plenty of ties
    observed = rng.random(300) < 0.9
    rows = [
        ("c", i // 6, i % 6, 5, -v, 0.0 if o else None)
        for i, (v, o) in enumerate(zip(values, observed, strict=True))
    ]
    ends = [None if o else 0.0 for o in observed]  # undelivered: censored at 0 - (-v) = v
    runs = ConditionRuns.from_log(log_from_rows(rows, run_end=_per_run(rows, ends)), "c")
    latencies = censored_latencies(runs)
    result = stats.ecdf(stats.CensoredData(uncensored=values[observed], right=values[~observed]))
    for q in (10, 50, 90, 95):
        expected = result.cdf.quantiles[np.argmax(result.cdf.probabilities >= q / 100 - 1e-9)]
        assert km_quantile(latencies, q) == expected
        ones = np.ones((1, runs.n_runs), dtype=np.int64)
        assert km_resampled_quantiles(latencies, ones, q, compiled=compiled)[0] == expected


def _per_run(rows, ends):
    """A run's end for each of its rows: its one given value (the rows of a run agree)."""
    by_run: dict[int, float] = {}
    for row, end in zip(rows, ends, strict=True):
        if end is not None:
            by_run[row[1]] = end
    return [by_run.get(row[1]) for row in rows]


def test_kaplan_meier_without_censoring_is_the_inverted_cdf_percentile():
    # 20 deliveries with latencies 1..20: the CDF is exactly 19/20 = 0.95 at 19.
    rows = [("c", run, 1, 5, 0.0, float(run + 1)) for run in range(20)]
    runs = ConditionRuns.from_log(log_from_rows(rows), "c")
    latencies = censored_latencies(runs)
    assert km_quantile(latencies, 95) == 19.0
    assert np.percentile(np.arange(1.0, 21.0), 95, method="inverted_cdf") == 19.0
    ones = np.ones((1, 20), dtype=np.int64)
    assert km_resampled_quantiles(latencies, ones, 95)[0] == 19.0  # the tolerance at work
    # One more carrier, never delivered, censored at 100: the CDF reaches 20/21 at 20.
    rows.append(("c", 20, 1, 5, 0.0, None))
    runs = ConditionRuns.from_log(log_from_rows(rows, run_end=[None] * 20 + [100.0]), "c")
    assert km_quantile(censored_latencies(runs), 95) == 20.0


@pytest.mark.parametrize("compiled", ENGINES)
def test_weighted_resamples_are_the_estimator_on_the_replicated_sample(runs, compiled):
    latencies = censored_latencies(runs)
    weights = next(iter_multiplicities(condition_generator(0, "c"), 4, 50, width=11))
    got = km_resampled_quantiles(latencies, weights, 50, compiled=compiled)
    by_run = [
        (latencies.values[latencies.runs == r], latencies.observed[latencies.runs == r])
        for r in range(4)
    ]
    for row, value in zip(weights, got, strict=True):
        sample = np.concatenate([np.tile(by_run[r][0], k) for r, k in enumerate(row)])
        events = np.concatenate([np.tile(by_run[r][1], k) for r, k in enumerate(row)])
        cdf = stats.ecdf(stats.CensoredData(uncensored=sample[events], right=sample[~events])).cdf
        reached = np.flatnonzero(cdf.probabilities >= 0.5 - 1e-9)
        if reached.size:
            assert value == cdf.quantiles[reached[0]], row
        else:
            assert np.isnan(value), row


def test_censoring_reverses_a_flattering_delivered_only_latency():
    # The baseline delivers everything at latency 50; the other delivers only its fast
    # carriers (latency 10) and leaves half of them waiting until the run ends at 200.
    rows, ends = [], []
    for run in range(8):
        for carrier in range(4):
            rows.append(("proximity", run, carrier, 5, 0.0, 50.0))
            rows.append(("other", run, carrier, 5, 0.0, 10.0 if carrier < 2 else None))
            ends += [200.0, 200.0]
    report = summarize(log_from_rows(rows, run_end=ends), n_resamples=300)
    by_metric = {k.metric: k for k in report.comparisons}
    assert by_metric["p95_latency"].diff == -40.0  # looks better delivered-only ...
    assert by_metric["mean_latency"].diff == -40.0
    assert by_metric["mean_latency_censored"].diff == pytest.approx(105.0 - 50.0)  # ... is not
    assert by_metric["p95_latency_censored"].diff == 150.0
    assert report.condition("other").km_p95_latency.value is None  # half never delivered
    assert by_metric["km_p95_latency"].diff is None
    assert all(k.undelivered_differs for k in report.comparisons)
    assert by_metric["pa"].undelivered == (16, 0)


def test_undelivered_shares_not_counts_decide_the_flag():
    one_of_five = [("proximity", 0, c, 5, 0.0, None if c == 0 else 9.0) for c in range(5)]
    two_of_ten = [
        ("other", r, c, 5, 0.0, None if c == 0 else 9.0) for r in (0, 1) for c in range(5)
    ]
    report = summarize(log_from_rows(one_of_five + two_of_ten), n_resamples=20)
    assert not any(k.undelivered_differs for k in report.comparisons)
    three_of_eleven = [*two_of_ten, ("other", 2, 0, 5, 0.0, None)]
    report = summarize(log_from_rows(one_of_five + three_of_eleven), n_resamples=20)
    assert all(k.undelivered_differs for k in report.comparisons)


def test_pa_at_delivery_ranks_by_urgency_end():
    # Run 0 of the worked example (docs/metrics.md): delivery order 1, 3, 4, 2; 5 undelivered.
    # urgency_end ranks 2 (9), then 3 and 4 (7, tie: 3 ordered earlier), 1 (5), 5 (0).
    # k = 1: {2} vs {1} -> 0; k = 2: {2,3} vs {1,3} -> 1/2; k = 3: {2,3,4} vs {1,3,4} -> 2/3.
    # k per p = 5..50 for n = 5: 1,1,1,1,2,2,2,2,3,3 -> (0 + 4/2 + 2 * 2/3) / 10 = 1/3.
    rows = [*ROWS[:5], ("c", 1, 1, 5, -4.0, 10.0), ("c", 1, 2, 8, -9.0, None)]
    urgency_end = [5, 9, 7, 7, 0, 6, None]  # run 1 lacks one: no PA at delivery for it
    log = log_from_rows(rows, urgency_end=urgency_end)
    runs = ConditionRuns.from_log(log, "c")
    values = run_values(runs)
    assert values.pa_at_delivery[0] == pytest.approx(1 / 3, rel=1e-15)
    assert np.isnan(values.pa_at_delivery[1])
    assert values.pa[0] == pytest.approx(28 / 30, rel=1e-15)  # PA itself ranks at run start
    kpis = condition_kpis(values)
    assert kpis.pa_at_delivery == pytest.approx(1 / 3, rel=1e-15)
    statistics = condition_statistics(runs, n_resamples=100, seed=2)
    assert statistics.metrics[-1] == "pa_at_delivery"
    assert statistics.pa_at_delivery is not None
    document = summarize(log, n_resamples=50).to_json()
    assert "pa_at_delivery" in document["conditions"][0]
    plain = summarize(log_from_rows(rows), n_resamples=50).to_json()
    assert "pa_at_delivery" not in plain["conditions"][0]


def _scipy_km(values: np.ndarray, observed: np.ndarray, q: float) -> float | None:
    cdf = stats.ecdf(stats.CensoredData(uncensored=values[observed], right=values[~observed])).cdf
    reached = np.flatnonzero(cdf.probabilities >= q / 100 - 1e-9)
    return float(cdf.quantiles[reached[0]]) if reached.size else None


@settings(max_examples=60)
@given(carrier_logs(conditions=("c",), max_runs=6), st.sampled_from([5, 50, 80, 95, 100]))
def test_the_point_value_is_scipys_without_importing_it(log, q):
    # With and without censoring, ties, everything censored: scipy.stats.ecdf's quantile.
    latencies = censored_latencies(ConditionRuns.from_log(log, "c"))
    assert km_quantile(latencies, q) == _scipy_km(latencies.values, latencies.observed, q)


@pytest.mark.parametrize("compiled", ENGINES)
@settings(max_examples=30)
@given(
    carrier_logs(conditions=("c",), max_runs=6),
    st.integers(0, 2**32 - 1),
    st.sampled_from([50, 90, 95]),
)
def test_resampled_kaplan_meier_is_scipys_on_each_replicated_sample(compiled, log, seed, q):
    latencies = censored_latencies(ConditionRuns.from_log(log, "c"))
    n_runs = int(latencies.runs.max()) + 1
    weights = multiplicities(np.random.default_rng(seed).integers(0, n_runs, (12, n_runs)), n_runs)
    got = km_resampled_quantiles(latencies, weights, q, compiled=compiled)
    for row, value in zip(weights, got, strict=True):
        counts = row[latencies.runs]
        expected = _scipy_km(
            np.repeat(latencies.values, counts), np.repeat(latencies.observed, counts), q
        )
        if expected is None:
            assert np.isnan(value), row
        else:
            assert value == expected, row


@pytest.mark.parametrize("compiled", ENGINES)
@settings(max_examples=40)
@given(carrier_logs(conditions=("c",), max_runs=8), st.integers(0, 2**32 - 1))
def test_counting_deaths_decides_exactly_what_the_product_decides(compiled, log, seed):
    # Where no censored value comes first, the KM CDF is deaths / n: the shortcut must agree
    # with the product-limit estimate computed in full, resample by resample.
    latencies = censored_latencies(ConditionRuns.from_log(log, "c"))
    n_runs = int(latencies.runs.max()) + 1
    weights = multiplicities(np.random.default_rng(seed).integers(0, n_runs, (40, n_runs)), n_runs)
    for q in (20, 50, 95):
        shortcut = km_resampled_quantiles(latencies, weights, q, compiled=compiled)
        with pytest.MonkeyPatch.context() as patch:
            patch.setattr(_kernels, "rank_targets", lambda totals, *_: np.full(totals.shape, -1))
            product = km_resampled_quantiles(latencies, weights, q, compiled=compiled)
        np.testing.assert_array_equal(shortcut, product)


def test_counting_deaths_is_left_to_the_product_where_rounding_could_decide():
    # level * n within rounding of an integer: the float product could fall either side.
    level = 0.95 - 1e-9
    targets = rank_targets(np.array([0, 1, 20, 21, 10**6]), level, 100)
    assert targets.tolist() == [-1, 1, 19, 20, 950_000]
    assert rank_targets(np.array([4, 5]), 0.5, 3).tolist() == [-1, 3]  # 2.0 exactly; 2.5
    assert rank_targets(np.array([4, 5]), 0.0, 3).tolist() == [-1, -1]
    assert rank_targets(np.array([4, 5]), float("nan"), 3).tolist() == [-1, -1]


@pytest.mark.parametrize("compiled", ENGINES)
def test_a_level_of_zero_is_reached_at_the_smallest_value(compiled, runs):
    # The product-limit CDF is 0 >= 0 at the first distinct value, censored or not.
    latencies = censored_latencies(runs)
    weights = np.array([[1, 1, 1, 1], [0, 2, 0, 2]])
    got = km_resampled_quantiles(latencies, weights, 1e-7, compiled=compiled)
    assert got.tolist() == [latencies.values[0]] * 2
