"""Differences from the baseline: pairing of bootstrap values, the p-value rule, Mann-Whitney."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.stats import mannwhitneyu

from swarmtag.analysis import (
    METRICS,
    ConditionRuns,
    bootstrap_p_value,
    compare,
    compare_all,
    condition_statistics,
    mann_whitney_p,
    summarize,
)
from swarmtag.errors import StatisticsError
from tests.io.strategies import log_from_rows


@pytest.mark.parametrize(
    ("differences", "expected"),
    [
        ([1.0, 2.0, -1.0, 3.0], 0.5),  # 2 * min(1, 3) / 4
        ([1.0, 2.0, 3.0], 0.0),  # no value <= 0
        ([0.0, 0.0, 0.0], 1.0),  # 2 * min(3, 3) / 3 = 2, capped at 1
        ([-1.0, 0.0, 1.0, 2.0], 1.0),  # 2 * min(2, 3) / 4 = 1
        ([-3.0, -2.0, -1.0, 0.0, 5.0], 0.8),  # 2 * min(4, 2) / 5
        ([np.nan, 1.0, -1.0, 2.0, 3.0], 0.5),  # NaN left out: B = 4
    ],
)
def test_bootstrap_p_value_rule(differences, expected):
    assert bootstrap_p_value(differences) == pytest.approx(expected)


def test_bootstrap_p_value_undefined():
    assert bootstrap_p_value([]) is None
    assert bootstrap_p_value([np.nan, np.nan]) is None


def test_mann_whitney_is_scipys_two_sided_test_without_missing_values():
    x = [3.0, np.nan, 5.0, 8.0, 1.0]
    y = [2.0, 9.0, np.nan, 7.0, 4.0, 6.0]
    expected = mannwhitneyu([3.0, 5.0, 8.0, 1.0], [2.0, 9.0, 7.0, 4.0, 6.0]).pvalue
    assert mann_whitney_p(x, y) == expected
    assert mann_whitney_p([np.nan], y) is None
    assert mann_whitney_p(x, []) is None


def _two_conditions(base: np.ndarray, other: np.ndarray, names=("proximity", "urgency")):
    rows = [(names[0], run, 1, 5, 0.0, float(x)) for run, x in enumerate(base)]
    rows += [(names[1], run, 1, 5, 0.0, float(x)) for run, x in enumerate(other)]
    return log_from_rows(rows)


def test_identical_conditions_give_large_p_values():
    # 60 runs of 4 carriers (one sometimes undelivered), logged twice under two names.
    rng = np.random.default_rng(4)
    rows = []
    for run in range(60):
        for carrier in range(4):
            delivered = carrier < 3 or rng.random() < 0.5
            delivery = float(rng.integers(5, 200)) if delivered else None
            urgency = int(rng.integers(0, 10))
            order = -float(rng.integers(0, 100))
            rows += [(name, run, carrier, urgency, order, delivery) for name in ("a", "b")]
    report = summarize(log_from_rows(rows), n_resamples=2000, seed=1)
    assert len(report.comparisons) == len(METRICS)
    for comparison in report.comparisons:
        assert comparison.diff == 0.0
        assert comparison.confidence_interval.low < 0 < comparison.confidence_interval.high or (
            comparison.confidence_interval.low == comparison.confidence_interval.high == 0.0
        )
        assert comparison.p_bootstrap > 0.5, comparison.metric
        if comparison.metric == "km_p95_latency":  # no per-run value: no Mann-Whitney test
            assert comparison.p_mannwhitney is None
        else:
            assert comparison.p_mannwhitney == pytest.approx(1.0), comparison.metric
        assert not comparison.undelivered_differs


def test_clearly_different_conditions_give_small_p_values():
    rng = np.random.default_rng(4)
    report = summarize(
        _two_conditions(rng.normal(200, 10, 40), rng.normal(100, 10, 40)), n_resamples=2000
    )
    mean = next(c for c in report.comparisons if c.metric == "mean_latency")
    assert mean.diff == pytest.approx(-100, abs=10)
    assert mean.confidence_interval.high < 0
    assert mean.p_bootstrap == 0.0
    assert mean.p_mannwhitney < 1e-6


def test_difference_pairs_the_two_conditions_own_bootstrap_values():
    rng = np.random.default_rng(9)
    log = _two_conditions(rng.exponential(60, 25), rng.exponential(40, 25))
    base = condition_statistics(ConditionRuns.from_log(log, "proximity"), n_resamples=400)
    other = condition_statistics(ConditionRuns.from_log(log, "urgency"), n_resamples=400)
    for comparison in compare_all(other, base):
        mine = other.estimate(comparison.metric).bootstrap_distribution
        theirs = base.estimate(comparison.metric).bootstrap_distribution
        np.testing.assert_array_equal(comparison.bootstrap_distribution, mine - theirs)
        assert comparison.p_bootstrap == bootstrap_p_value(mine - theirs)
        assert comparison.p_mannwhitney == mann_whitney_p(
            other.values.per_run(comparison.metric), base.values.per_run(comparison.metric)
        )
    assert [c.metric for c in compare_all(other, base)] == list(METRICS)


def test_undefined_figures_give_null_differences():
    # The other condition never delivers: no latency, no throughput, nothing to test.
    rows = [("proximity", run, 1, 5, 0.0, 10.0 + run) for run in range(4)]
    rows += [("proximity", run, 2, 5, 0.0, 30.0 + run) for run in range(4)]
    rows += [("stuck", run, 1, 5, 0.0, None) for run in range(4)]
    report = summarize(log_from_rows(rows), n_resamples=100)
    by_metric = {c.metric: c for c in report.comparisons}
    for metric in ("p95_latency", "mean_latency", "throughput"):
        comparison = by_metric[metric]
        assert comparison.diff is None
        assert (comparison.confidence_interval.low, comparison.confidence_interval.high) == (
            None,
            None,
        )
        assert comparison.p_bootstrap is None
        assert comparison.p_mannwhitney is None
    assert by_metric["deliveries_per_run"].diff == -2.0


def test_comparing_different_resample_counts_is_refused():
    log = _two_conditions(np.arange(1.0, 6.0), np.arange(2.0, 7.0))
    base = condition_statistics(ConditionRuns.from_log(log, "proximity"), n_resamples=10)
    other = condition_statistics(ConditionRuns.from_log(log, "urgency"), n_resamples=20)
    with pytest.raises(StatisticsError, match="resamples"):
        compare(other, base, "pa")
    with pytest.raises(StatisticsError, match="unknown metric"):
        compare(base, base, "speed")


@pytest.mark.parametrize(("first", "second"), [(2, 2), (3, 3), (4, 6), (5, 5), (10, 10)])
def test_the_smallest_mann_whitney_p_is_scipys_for_samples_that_do_not_overlap(first, second):
    import scipy.stats

    from swarmtag.analysis.compare import smallest_mann_whitney_p

    low, high = np.arange(first, dtype=float), np.arange(second, dtype=float) + 100
    exact = scipy.stats.mannwhitneyu(low, high, alternative="two-sided", method="exact").pvalue
    assert smallest_mann_whitney_p(first, second) == pytest.approx(exact)


def test_the_tests_of_all_metrics_are_one_scipy_call_with_scipys_p_values(monkeypatch):
    # 25 runs a side, no value missing: every metric's samples have one size, above the
    # eight where scipy would test exactly; the batched p-values are scipy's, bit for bit.
    import scipy.stats

    rng = np.random.default_rng(9)
    log = _two_conditions(rng.exponential(60, 25), rng.exponential(40, 25))
    base = condition_statistics(ConditionRuns.from_log(log, "proximity"), n_resamples=50)
    other = condition_statistics(ConditionRuns.from_log(log, "urgency"), n_resamples=50)
    calls = []

    def counted(*args, **kwargs):
        calls.append(np.shape(args[0]))
        return mannwhitneyu(*args, **kwargs)

    monkeypatch.setattr(scipy.stats, "mannwhitneyu", counted)
    comparisons = compare_all(other, base)
    tested = [c for c in comparisons if c.p_mannwhitney is not None]
    assert len(tested) >= 6
    assert calls == [(len(tested), 25)]
    for comparison in tested:
        expected = mannwhitneyu(
            other.values.per_run(comparison.metric), base.values.per_run(comparison.metric)
        ).pvalue
        assert comparison.p_mannwhitney == expected, comparison.metric


def test_small_samples_are_tested_one_pair_at_a_time():
    # Ties in one pair of small samples make scipy test that pair asymptotically; batched
    # with a pair without ties, they would switch that one too: small pairs go one by one.
    from swarmtag.analysis.compare import _mann_whitney_ps

    tied = ([1.0, 1.0, 2.0, 3.0], [2.0, 4.0, 5.0, 6.0])
    untied = ([1.0, 2.0, 3.0, 7.0], [4.0, 5.0, 6.0, 8.0])
    large = (np.arange(10.0), np.arange(10.0) + 0.5)
    missing = ([np.nan], [1.0])
    pairs = [tied, untied, large, missing, (None, [1.0])]
    expected = [mannwhitneyu(*pair).pvalue for pair in pairs[:3]]
    assert _mann_whitney_ps(pairs) == [*expected, None, None]
    assert expected[1] == mannwhitneyu(*untied, method="exact").pvalue


def test_a_tester_given_by_mann_whitney_by_gets_the_samples_and_gives_the_p_values():
    from swarmtag.analysis.compare import _mann_whitney_ps, mann_whitney_by, mann_whitney_ps

    pairs = [([1.0, np.nan, 3.0], [2.0, 4.0]), ([np.nan], [1.0]), ([5.0, 6.0], [1.0, 2.0])]
    asked = []

    def tester(samples):
        asked.append(samples)
        return [0.25, None, 0.5]

    with mann_whitney_by(tester):
        assert _mann_whitney_ps(pairs) == [0.25, None, 0.5]
        assert _mann_whitney_ps([([np.nan], [1.0])]) == [None]  # nothing to test: not asked
    (samples,) = asked
    assert [None if s is None else (s[0].tolist(), s[1].tolist()) for s in samples] == [
        ([1.0, 3.0], [2.0, 4.0]),
        None,
        ([5.0, 6.0], [1.0, 2.0]),
    ]
    assert mann_whitney_ps(samples) == _mann_whitney_ps(pairs)  # outside: computed here
    assert _mann_whitney_ps(pairs)[0] == mannwhitneyu([1.0, 3.0], [2.0, 4.0]).pvalue
