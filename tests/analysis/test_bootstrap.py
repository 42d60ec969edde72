"""Bootstrap over runs: exact intervals, re-pooling, undefined resamples, seeding, options."""

from __future__ import annotations

import hashlib
import math
import subprocess
import sys
import textwrap

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from swarmtag.analysis import (
    METRICS,
    ConditionRuns,
    condition_statistics,
    percentile_interval,
    run_values,
    summarize,
)
from swarmtag.analysis import bootstrap as bootstrap_module
from swarmtag.analysis._kernels import numba_available
from swarmtag.analysis.resampling import condition_generator
from swarmtag.errors import StatisticsError
from swarmtag.io import CarrierLog
from tests.io.strategies import carrier_logs, log_from_rows

needs_numba = pytest.mark.skipif(not numba_available(), reason="numba (the fast extra) is absent")
ENGINES = [pytest.param(False, id="numpy"), pytest.param(True, id="compiled", marks=needs_numba)]
"""Both implementations of the bootstrap's kernels: they must give the same bits."""


def _one_delivery_per_run(latencies: np.ndarray, name: str = "c") -> CarrierLog:
    return log_from_rows([(name, run, 1, 5, 0.0, float(x)) for run, x in enumerate(latencies)])


def test_ci_of_the_mean_matches_the_analytic_interval():
    # 2000 runs, one delivery each: mean latency is the mean of a normal sample, whose 95 %
    # interval is mean +- 1.96 s / sqrt(n). The bootstrap interval must agree within a few %.
    latencies = np.random.default_rng(1).normal(100.0, 15.0, 2000)
    runs = ConditionRuns.from_log(_one_delivery_per_run(latencies), "c")
    ci = condition_statistics(runs, n_resamples=10_000, seed=4).mean_latency.confidence_interval
    mean = latencies.mean()
    half = 1.959964 * latencies.std(ddof=1) / math.sqrt(latencies.size)
    assert ci.high - ci.low == pytest.approx(2 * half, rel=0.04)
    assert (ci.low + ci.high) / 2 == pytest.approx(mean, abs=0.04 * half)


def test_interval_is_numpys_2_5_and_97_5_percentiles_without_undefined():
    values = np.random.default_rng(2).normal(size=1001)
    with_gaps = np.concatenate([values, [np.nan, np.nan]])
    ci = percentile_interval(with_gaps)
    low, high = np.percentile(values, [2.5, 97.5])
    assert (ci.low, ci.high) == (low, high)
    ci90 = percentile_interval(values, confidence_level=0.9)
    assert (ci90.low, ci90.high) == tuple(np.percentile(values, [5, 95]))


def _censored_by_run(runs: ConditionRuns) -> list[tuple[np.ndarray, np.ndarray]]:
    """Per run: every carrier's latency or (run end - order time), and whether delivered."""
    result = []
    for run in range(runs.n_runs):
        rows = runs.run_index == run
        given = runs.run_end[rows][~np.isnan(runs.run_end[rows])]
        times = np.concatenate([runs.pickup_time[rows], runs.delivery_time[rows]])
        times = times[~np.isnan(times)]
        end = given[0] if given.size else (times.max() if times.size else 0.0)
        delivered = runs.delivered[rows]
        ends = np.where(delivered, runs.delivery_time[rows], end)
        result.append((ends - runs.order_time[rows], delivered))
    return result


def _scipy_km_p95(values: np.ndarray, observed: np.ndarray) -> float:
    from scipy import stats

    data = stats.CensoredData(uncensored=values[observed], right=values[~observed])
    cdf = stats.ecdf(data).cdf
    reached = np.flatnonzero(cdf.probabilities >= 0.95 - 1e-9)
    return float(cdf.quantiles[reached[0]]) if reached.size else np.nan


def _reference_replicates(runs: ConditionRuns, n_resamples: int, seed: int) -> dict[str, list]:
    """Slow and obvious: draw runs, concatenate them, compute each figure from scratch."""
    rng = condition_generator(seed, runs.condition)
    draws = rng.integers(0, runs.n_runs, size=(n_resamples, runs.n_runs))
    latency = runs.delivery_time - runs.order_time
    per_run = run_values(runs)
    censored = _censored_by_run(runs)
    result: dict[str, list] = {metric: [] for metric in (*METRICS, "pa_at_delivery")}
    for drawn in draws:
        values = np.concatenate([censored[run][0] for run in drawn])
        observed = np.concatenate([censored[run][1] for run in drawn])
        result["p95_latency_censored"].append(np.percentile(values, 95))
        result["mean_latency_censored"].append(np.mean(values))
        result["km_p95_latency"].append(_scipy_km_p95(values, observed))
        at_delivery = per_run.pa_at_delivery[drawn]
        at_delivery = at_delivery[~np.isnan(at_delivery)]
        result["pa_at_delivery"].append(np.mean(at_delivery) if at_delivery.size else np.nan)
        pooled = np.concatenate(
            [latency[(runs.run_index == run) & runs.delivered] for run in drawn]
        )
        throughputs = per_run.throughput[drawn]
        throughputs = throughputs[~np.isnan(throughputs)]
        result["p95_latency"].append(np.percentile(pooled, 95) if pooled.size else np.nan)
        result["mean_latency"].append(np.mean(pooled) if pooled.size else np.nan)
        result["throughput"].append(np.mean(throughputs) if throughputs.size else np.nan)
        result["pa"].append(np.mean(per_run.pa[drawn]))
        result["deliveries_per_run"].append(np.mean(per_run.deliveries[drawn]))
    if np.isnan(_scipy_km_p95(*_pooled(censored))):  # undefined for the condition: for all
        result["km_p95_latency"] = [np.nan] * n_resamples
    return result


@pytest.mark.parametrize("compiled", ENGINES)
@settings(max_examples=25)
@given(carrier_logs(conditions=("c",), max_runs=6), st.integers(0, 1000))
def test_bootstrap_values_equal_the_slow_reference(compiled, log, seed):
    runs = ConditionRuns.from_log(log, "c")
    statistics = condition_statistics(runs, n_resamples=60, seed=seed, compiled=compiled)
    reference = _reference_replicates(runs, 60, seed)
    # Percentiles are exact to the bit; sums in another order may differ in the last bits.
    for metric in ("p95_latency", "p95_latency_censored", "km_p95_latency"):
        np.testing.assert_array_equal(
            statistics.estimate(metric).bootstrap_distribution, reference[metric], err_msg=metric
        )
    if statistics.km_p95_latency.value is None:  # never reached: undefined in every resample
        assert statistics.km_p95_latency.n_undefined == 60
    else:
        assert statistics.km_p95_latency.value == _scipy_km_p95(*_pooled(_censored_by_run(runs)))
    others = [
        m for m in METRICS if m not in ("p95_latency", "p95_latency_censored", "km_p95_latency")
    ]
    if statistics.pa_at_delivery is not None:
        others.append("pa_at_delivery")
    for metric in others:
        np.testing.assert_allclose(
            statistics.estimate(metric).bootstrap_distribution,
            reference[metric],
            rtol=1e-12,
            atol=1e-12,
            err_msg=metric,
        )


def _pooled(by_run: list[tuple[np.ndarray, np.ndarray]]) -> tuple[np.ndarray, np.ndarray]:
    return np.concatenate([v for v, _ in by_run]), np.concatenate([o for _, o in by_run])


def test_resamples_without_a_value_are_left_out():
    # Five runs; only run 0 has deliveries (two of them, 10 time units apart).
    rows = [("c", 0, 1, 5, 0.0, 10.0), ("c", 0, 2, 5, 0.0, 20.0)]
    rows += [("c", run, 1, 5, 0.0, None) for run in range(1, 5)]
    statistics = condition_statistics(
        ConditionRuns.from_log(log_from_rows(rows), "c"), n_resamples=500, seed=1
    )
    for metric in ("p95_latency", "mean_latency", "throughput"):
        estimate = statistics.estimate(metric)
        distribution = estimate.bootstrap_distribution
        # A resample without run 0 has no latency and no throughput: (4/5)^5 of them, ~33 %.
        assert 100 < estimate.n_undefined < 240
        assert estimate.n_undefined == int(np.isnan(distribution).sum())
        defined = distribution[~np.isnan(distribution)]
        ci = estimate.confidence_interval
        assert (ci.low, ci.high) == tuple(np.percentile(defined, [2.5, 97.5]))
    assert statistics.throughput.value == 20.0  # 100 * 2 / (20 - 10)
    assert statistics.pa.n_undefined == 0
    assert statistics.deliveries_per_run.n_undefined == 0


def test_undefined_everywhere_gives_no_interval():
    rows = [("c", run, 1, 5, 0.0, None) for run in range(3)]
    statistics = condition_statistics(
        ConditionRuns.from_log(log_from_rows(rows), "c"), n_resamples=50
    )
    for metric in ("p95_latency", "mean_latency", "throughput"):
        estimate = statistics.estimate(metric)
        assert estimate.value is None
        assert (estimate.confidence_interval.low, estimate.confidence_interval.high) == (None, None)
        assert estimate.n_undefined == 50
    assert statistics.deliveries_per_run.confidence_interval.low == 0.0


def test_same_seed_same_result_other_seed_other_result():
    latencies = np.random.default_rng(0).exponential(50.0, 40)
    runs = ConditionRuns.from_log(_one_delivery_per_run(latencies), "c")
    first = condition_statistics(runs, n_resamples=300, seed=7)
    again = condition_statistics(runs, n_resamples=300, seed=7)
    other = condition_statistics(runs, n_resamples=300, seed=8)
    for metric in METRICS:
        np.testing.assert_array_equal(
            first.estimate(metric).bootstrap_distribution,
            again.estimate(metric).bootstrap_distribution,
        )
    assert not np.array_equal(
        first.mean_latency.bootstrap_distribution, other.mean_latency.bootstrap_distribution
    )


def test_memory_chunking_does_not_change_results():
    latencies = np.random.default_rng(5).exponential(50.0, 30)
    runs = ConditionRuns.from_log(_one_delivery_per_run(latencies), "c")
    whole = condition_statistics(runs, n_resamples=200, seed=3)
    chunked = condition_statistics(runs, n_resamples=200, seed=3, _chunk_elements=64)
    for metric in METRICS:
        np.testing.assert_array_equal(
            whole.estimate(metric).bootstrap_distribution,
            chunked.estimate(metric).bootstrap_distribution,
        )


def test_bootstrap_values_are_read_only():
    runs = ConditionRuns.from_log(_one_delivery_per_run(np.arange(1.0, 6.0)), "c")
    distribution = condition_statistics(runs, n_resamples=10).pa.bootstrap_distribution
    with pytest.raises(ValueError, match="read-only"):
        distribution[0] = 1.0


@pytest.mark.parametrize(
    ("options", "message"),
    [
        ({"n_resamples": 0}, "n_resamples"),
        ({"n_resamples": 2.5}, "n_resamples"),
        ({"seed": -1}, "seed"),
        ({"confidence_level": 1.0}, "confidence_level"),
        ({"confidence_level": 95}, "confidence_level"),
        ({"curve_thresholds": [5, 101]}, "curve_thresholds"),
        ({"curve_percentiles": [-1]}, "curve_percentiles"),
    ],
)
def test_bad_options_are_refused(options, message):
    runs = ConditionRuns.from_log(_one_delivery_per_run(np.arange(1.0, 6.0)), "c")
    with pytest.raises(StatisticsError, match=message):
        condition_statistics(runs, **options)


def test_numpy_numbers_are_fine_options():
    runs = ConditionRuns.from_log(_one_delivery_per_run(np.arange(1.0, 6.0)), "c")
    plain = condition_statistics(runs, n_resamples=20, seed=2, confidence_level=0.9)
    numpy = condition_statistics(
        runs, n_resamples=np.int64(20), seed=np.uint32(2), confidence_level=np.float64(0.9)
    )
    assert numpy.pa.confidence_interval == plain.pa.confidence_interval


def _pinned_log(seed: int, n_runs: int, carriers: int, delivered_share: float) -> CarrierLog:
    """Runs with ties, undelivered carriers, ``run_end`` and ``urgency_end``."""
    rng = np.random.default_rng(seed)
    rows, ends, urgency_end = [], [], []
    for run in range(n_runs):
        end = float(rng.integers(40, 60))
        for carrier in range(carriers):
            order = -float(rng.integers(0, 9))
            delivery = float(rng.integers(1, 40)) if rng.random() < delivered_share else None
            rows.append(("c", run, carrier, int(rng.integers(0, 10)), order, delivery))
            ends.append(end)
            urgency_end.append(int(rng.integers(0, 10)))
    return log_from_rows(rows, run_end=ends, urgency_end=urgency_end)


def _digest(values: np.ndarray) -> str:
    return hashlib.sha256(np.asarray(values, dtype="<f8").tobytes()).hexdigest()[:16]


# Computed by the implementation before the kernels (every resample re-pooled with numpy
# arrays of resamples x values): the same seed must give the same numbers, bit for bit where no
# BLAS sum is involved. Case 1: KM P95 defined with censoring (the death count decides most
# resamples, the product the rest); case 2: KM P95 undefined; case 3: nothing censored.
PINNED = {
    (1, 14, 6, 0.97): (
        ("67b52bbbb5d735a7", "0890fe152ad1103c", "34a577d718b80f93", "a595a81384b2d6a8"),
        {
            "p95_latency": (39.0, 45.0),
            "mean_latency": (23.433562297972376, 28.671036585365854),
            "throughput": (21.91265859979674, 28.200524884491525),
            "pa": (0.23690476190476187, 0.4023809523809523),
            "deliveries_per_run": (5.642857142857143, 6.0),
            "p95_latency_censored": (39.849999999999994, 47.69999999999999),
            "mean_latency_censored": (23.928571428571427, 29.13125),
            "km_p95_latency": (40.0, 46.0),
            "pa_at_delivery": (0.22857142857142856, 0.41190476190476183),
        },
    ),
    (2, 9, 5, 0.8): (
        ("8dddd143c66e7803", "ccdf2b805b80606e", "dfdcf2bc4524cc2b", "b9c1e05eb47dadd2"),
        {
            "p95_latency": (41.09875, 46.0),
            "mean_latency": (24.617357397504456, 30.585365853658537),
            "throughput": (13.843474136348531, 19.28764303745563),
            "pa": (0.28148148148148144, 0.5925925925925926),
            "deliveries_per_run": (3.6666666666666665, 4.666666666666667),
            "p95_latency_censored": (46.0, 61.199999999999974),
            "mean_latency_censored": (29.08888888888889, 33.44444444444444),
            "km_p95_latency": (None, None),
            "pa_at_delivery": (0.22962962962962966, 0.6222222222222222),
        },
    ),
    (3, 25, 4, 1.0): (
        ("fe6a62e2dd1f0450", "fe6a62e2dd1f0450", "850d78f9ff14c0fc", "faf9c50a12bd8900"),
        {
            "p95_latency": (38.0, 42.099999999999994),
            "mean_latency": (21.46, 26.68),
            "throughput": (19.2710096004886, 28.962726981660154),
            "pa": (0.31, 0.56),
            "deliveries_per_run": (4.0, 4.0),
            "p95_latency_censored": (38.0, 42.099999999999994),
            "mean_latency_censored": (21.46, 26.68),
            "km_p95_latency": (38.0, 42.0),
            "pa_at_delivery": (0.28, 0.53),
        },
    ),
}


@pytest.mark.parametrize("compiled", ENGINES)
@pytest.mark.parametrize("case", list(PINNED))
def test_the_same_seed_gives_the_numbers_it_always_gave(case, compiled):
    runs = ConditionRuns.from_log(_pinned_log(*case), "c")
    statistics = condition_statistics(runs, n_resamples=4000, seed=case[0], compiled=compiled)
    digests, intervals = PINNED[case]
    exact = ("p95_latency", "p95_latency_censored", "km_p95_latency")
    got = [_digest(statistics.estimate(m).bootstrap_distribution) for m in exact]
    curve = statistics.latency_curve
    assert [*got, _digest(np.concatenate([curve.low, curve.high]))] == list(digests)
    for metric, (low, high) in intervals.items():
        interval = statistics.estimate(metric).confidence_interval
        if metric in exact or low is None:
            assert (interval.low, interval.high) == (low, high), metric
        else:  # sums over runs (BLAS): the last bits may depend on the machine's library
            assert interval.low == pytest.approx(low, rel=1e-12), metric
            assert interval.high == pytest.approx(high, rel=1e-12), metric


@pytest.mark.parametrize("case", list(PINNED))
@pytest.mark.skipif(not numba_available(), reason="numba (the fast extra) is absent")
def test_numpy_and_compiled_kernels_give_the_same_bits(case):
    log = _pinned_log(*case)
    first = summarize(log, n_resamples=700, seed=9, compiled=False)
    second = summarize(log, n_resamples=700, seed=9, compiled=True)
    assert first.to_json() == second.to_json()
    for mine, theirs in zip(first.conditions, second.conditions, strict=True):
        for metric in mine.metrics:
            np.testing.assert_array_equal(
                mine.estimate(metric).bootstrap_distribution,
                theirs.estimate(metric).bootstrap_distribution,
                err_msg=metric,
            )
        for curve in ("latency_curve", "pa_curve"):
            for bound in ("low", "high"):
                np.testing.assert_array_equal(
                    getattr(getattr(mine, curve), bound), getattr(getattr(theirs, curve), bound)
                )


def test_an_undefined_kaplan_meier_p95_is_not_computed(monkeypatch):
    rows_seen = []
    original = bootstrap_module.km_resampled_quantiles

    def counted(latencies, weights, *args, **kwargs):
        rows_seen.append(len(weights))
        return original(latencies, weights, *args, **kwargs)

    monkeypatch.setattr(bootstrap_module, "km_resampled_quantiles", counted)
    undefined = ConditionRuns.from_log(_pinned_log(2, 9, 5, 0.8), "c")
    statistics = condition_statistics(undefined, n_resamples=300, _chunk_elements=45 * 100)
    assert statistics.km_p95_latency.value is None
    assert statistics.km_p95_latency.n_undefined == 300
    assert rows_seen == [0, 0, 0]  # called for each chunk, on no resample
    rows_seen.clear()
    defined = ConditionRuns.from_log(_pinned_log(1, 14, 6, 0.97), "c")
    condition_statistics(defined, n_resamples=300, _chunk_elements=84 * 100)
    assert rows_seen == [100, 100, 100]


def test_scipy_stats_is_loaded_only_for_mann_whitney():
    # scipy.stats takes a second or so to import: KPIs and intervals do without it.
    script = textwrap.dedent(
        """
        import sys
        from swarmtag.analysis import ConditionRuns, condition_statistics, summarize
        from tests.io.strategies import log_from_rows

        # Undelivered carriers ordered late: censored at 5, among the deliveries (1 to 9).
        rows = [("c", r, i, 5, 55.0, None) if (r + i) % 7 == 0 else ("c", r, i, 5, 0.0, r + i + 1.0)
                for r in range(6) for i in range(4)]
        log = log_from_rows(rows, run_end=[60.0] * len(rows))
        statistics = condition_statistics(ConditionRuns.from_log(log, "c"), n_resamples=200)
        assert statistics.km_p95_latency.value is not None
        summarize(log, n_resamples=200)
        assert "scipy.stats" not in sys.modules, "loaded without a comparison"
        other = [("d", *row[1:]) for row in rows]
        summarize(log_from_rows(rows + other, run_end=[60.0] * 2 * len(rows)), n_resamples=50)
        assert "scipy.stats" in sys.modules
        """
    )
    done = subprocess.run(
        [sys.executable, "-c", script], capture_output=True, text=True, check=False, timeout=300
    )
    assert done.returncode == 0, done.stderr
