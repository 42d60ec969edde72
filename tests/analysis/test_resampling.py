"""Resampling whole runs: multiplicities, exact re-pooled percentiles (numpy and compiled
kernels alike), seeded streams."""

from __future__ import annotations

import os
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from threadpoolctl import threadpool_info, threadpool_limits

from swarmtag.analysis import (
    ConditionRuns,
    choice_statistics,
    condition_seed_sequence,
    run_values,
    summarize,
)
from swarmtag.analysis._kernels import (
    COMPILE_WORTH,
    numba_available,
    use_compiled,
    weighted_positions,
)
from swarmtag.analysis.resampling import (
    condition_generator,
    iter_multiplicities,
    multiplicities,
    one_blas_thread,
    resampled_percentiles,
)
from swarmtag.io import CarrierLog, EventTable
from tests.io.strategies import carrier_logs

needs_numba = pytest.mark.skipif(not numba_available(), reason="numba (the fast extra) is absent")
ENGINES = [pytest.param(False, id="numpy"), pytest.param(True, id="compiled", marks=needs_numba)]
"""Both implementations of the kernels: they must give the same bits."""


def test_multiplicities_count_draws():
    draws = np.array([[0, 0, 0], [2, 1, 0], [1, 1, 2]])
    assert multiplicities(draws, 3).tolist() == [[3, 0, 0], [1, 1, 1], [0, 2, 1]]


@given(st.integers(1, 50), st.integers(1, 40), st.integers(0, 2**32 - 1))
def test_multiplicity_rows_sum_to_the_number_of_runs(n_runs, n_resamples, seed):
    rng = np.random.default_rng(seed)
    counts = multiplicities(rng.integers(0, n_runs, size=(n_resamples, n_runs)), n_runs)
    assert counts.shape == (n_resamples, n_runs)
    assert (counts.sum(axis=1) == n_runs).all()


@pytest.mark.parametrize("compiled", ENGINES)
@given(carrier_logs(conditions=("c",), max_runs=8), st.integers(0, 2**32 - 1))
def test_repooled_percentiles_equal_numpy_on_concatenated_resamples(compiled, log, seed):
    """The fast weighted order statistics against the slow, obvious reference."""
    values = run_values(ConditionRuns.from_log(log, "c"))
    latencies = values.latencies
    rng = np.random.default_rng(seed)
    draws = rng.integers(0, values.n_runs, size=(30, values.n_runs))
    percentiles = [95, 0, 2.5, 50, 97.5, 100, 33.3]
    fast = resampled_percentiles(
        latencies.values,
        latencies.runs,
        multiplicities(draws, values.n_runs),
        percentiles,
        compiled=compiled,
    )
    per_run = [latencies.values[latencies.runs == run] for run in range(values.n_runs)]
    for row, drawn in enumerate(draws):
        sample = np.concatenate([per_run[run] for run in drawn])
        if sample.size == 0:
            assert np.isnan(fast[row]).all()
        else:
            np.testing.assert_array_equal(fast[row], np.percentile(sample, percentiles))


def test_chunks_do_not_change_the_draws():
    whole = list(iter_multiplicities(condition_generator(5, "c"), 13, 101, width=13))
    small = list(
        iter_multiplicities(condition_generator(5, "c"), 13, 101, width=13, chunk_elements=50)
    )
    assert (len(whole), len(small)) == (1, 34)  # 50 // 13 = 3 resamples per chunk
    np.testing.assert_array_equal(np.vstack(whole), np.vstack(small))


def test_streams_are_keyed_by_seed_and_condition_name():
    def first_draws(seed: int, name: str) -> list[int]:
        return condition_generator(seed, name).integers(0, 1000, 8).tolist()

    assert first_draws(0, "proximity") == first_draws(0, "proximity")
    assert first_draws(0, "proximity") != first_draws(1, "proximity")
    assert first_draws(0, "proximity") != first_draws(0, "urgency:alpha=0.7")
    assert condition_seed_sequence(3, "x").entropy == 3


@pytest.mark.parametrize(
    ("name", "key"),
    [("proximity", 233343916854633), ("urgency:alpha=0.7", 5887698059998736234)],
)
def test_spawn_key_is_pinned(name, key):
    # The first 8 bytes of SHA-256 of the name, little-endian. Pinned: changing the keying would
    # silently change every published confidence interval.
    assert condition_seed_sequence(0, name).spawn_key == (key,)


def _explicit_percentiles(
    values: np.ndarray, groups: np.ndarray, weights: np.ndarray, percentiles: list[float]
) -> np.ndarray:
    """The obvious reference: build each resample's pooled sample and ask numpy."""
    result = np.full((len(weights), len(percentiles)), np.nan)
    for row, counts in enumerate(weights):
        sample = np.repeat(values, counts[groups])
        if sample.size:
            result[row] = np.percentile(sample, percentiles)
    return result


@pytest.mark.parametrize("compiled", ENGINES)
@settings(max_examples=60)
@given(
    st.lists(st.integers(0, 12), min_size=1, max_size=40),
    st.integers(1, 7),
    st.lists(st.floats(0, 100), max_size=6),
    st.integers(0, 2**32 - 1),
)
def test_both_kernels_give_numpys_percentiles_with_ties_and_empty_resamples(
    compiled, sample, n_runs, extra, seed
):
    rng = np.random.default_rng(seed)
    values = np.sort(np.asarray(sample, dtype=np.float64))  # integers: plenty of ties
    groups = rng.integers(0, n_runs, values.size)
    weights = rng.integers(0, 4, size=(25, n_runs)) * (rng.random((25, n_runs)) < 0.6)
    weights[0] = 0  # an empty resample
    percentiles = [95, 0, 100, 50, 2.5, 97.5, *extra]
    got = resampled_percentiles(values, groups, weights, percentiles, compiled=compiled)
    expected = _explicit_percentiles(values, groups, weights, percentiles)
    np.testing.assert_array_equal(got, expected)
    assert np.isnan(got[0]).all()


@pytest.mark.parametrize("compiled", ENGINES)
def test_percentiles_go_into_a_strided_view(compiled):
    rng = np.random.default_rng(4)
    values = np.sort(rng.exponential(30.0, 200))
    groups = rng.integers(0, 20, 200)
    weights = multiplicities(rng.integers(0, 20, size=(300, 20)), 20)
    percentiles = [95, *range(0, 101, 5)]
    whole = resampled_percentiles(values, groups, weights, percentiles, compiled=compiled)
    rows = np.full((len(percentiles), 400), -1.0)
    out = rows[:, 50:350].T  # columns of a (Q, B) array, as the bootstrap keeps its curves
    returned = resampled_percentiles(
        values, groups, weights, percentiles, compiled=compiled, out=out
    )
    assert returned is out
    np.testing.assert_array_equal(out, whole)
    assert (rows[:, :50] == -1.0).all()
    assert (rows[:, 350:] == -1.0).all()
    np.testing.assert_array_equal(
        whole, _explicit_percentiles(values, groups, weights, percentiles)
    )


@given(
    st.lists(st.integers(0, 5), min_size=1, max_size=30),
    st.integers(0, 2**32 - 1),
)
def test_weighted_positions_are_the_first_cumulative_weight_above_the_rank(run_of, seed):
    rng = np.random.default_rng(seed)
    groups = np.asarray(run_of)
    weights = rng.integers(0, 3, size=(12, 6))
    weights[:, groups[0]] += 1  # every row holds something
    totals = weights[:, groups].sum(axis=1)
    ranks = (rng.random((12, 5)) * totals[:, None]).astype(np.int64)
    got = weighted_positions(groups, weights, ranks)
    for row in range(12):
        cumulative = np.cumsum(weights[row, groups])
        expected = [int(np.argmax(cumulative > rank)) for rank in ranks[row]]
        assert got[row].tolist() == expected
        pooled = np.repeat(np.arange(groups.size), weights[row, groups])  # the pooled sample
        assert got[row].tolist() == pooled[ranks[row]].tolist()


def test_the_compiled_kernels_run_only_where_they_pay():
    assert use_compiled(10) is False
    if numba_available():
        assert use_compiled(COMPILE_WORTH) is True
    else:
        assert use_compiled(10**12) is False


@pytest.mark.parametrize("compiled", ENGINES)
@given(st.integers(1, 50), st.integers(1, 40), st.integers(0, 2**32 - 1))
def test_both_ways_of_counting_draws_agree(compiled, n_runs, n_resamples, seed):
    draws = np.random.default_rng(seed).integers(0, n_runs, size=(n_resamples, n_runs))
    expected = [np.bincount(row, minlength=n_runs).tolist() for row in draws]
    assert multiplicities(draws, n_runs, compiled=compiled).tolist() == expected
    chunks = iter_multiplicities(
        condition_generator(seed, "c"), n_runs, n_resamples, width=n_runs, compiled=compiled
    )
    plain = iter_multiplicities(condition_generator(seed, "c"), n_runs, n_resamples, width=n_runs)
    np.testing.assert_array_equal(np.vstack(list(chunks)), np.vstack(list(plain)))


def _blas_threads() -> list[int]:
    """The thread count of each BLAS library loaded when the bootstraps first ran (numpy's)."""
    with one_blas_thread():  # the libraries it limits are those loaded then, numpy's included
        pass
    numpy_blas = Path(np.__file__).parent.with_name("numpy.libs")
    pools = [pool for pool in threadpool_info() if pool["user_api"] == "blas"]
    limited = [pool for pool in pools if Path(pool["filepath"]).parent == numpy_blas]
    return [pool["num_threads"] for pool in limited or pools]


def test_one_blas_thread_limits_blas_to_one_thread_and_then_restores_it():
    before = _blas_threads()
    if not before:
        pytest.skip("threadpoolctl finds no BLAS library to limit in this numpy")
    with one_blas_thread():
        assert _blas_threads() == [1] * len(before)
    assert _blas_threads() == before


def test_a_chunk_product_on_one_blas_thread_has_the_same_bits_as_on_every_core():
    # the bootstrap's products, of chunk size: one thread must not change the numbers
    rng = np.random.default_rng(5)
    weights = multiplicities(rng.integers(0, 100, size=(4000, 100)), 100).astype(np.float64)
    per_run = rng.normal(30.0, 12.0, size=(100, 25))
    with threadpool_limits(limits=max(2, os.cpu_count() or 1), user_api="blas"):
        threaded = weights @ per_run
    with one_blas_thread():
        alone = weights @ per_run
    assert threaded.tobytes() == alone.tobytes()


def test_the_bootstraps_draw_their_products_on_one_blas_thread(monkeypatch):
    inside: list[list[int]] = []

    @contextmanager
    def spy() -> Iterator[None]:
        with one_blas_thread():
            inside.append(_blas_threads())
            yield

    monkeypatch.setattr("swarmtag.analysis.bootstrap.one_blas_thread", spy)
    monkeypatch.setattr("swarmtag.analysis.choices.one_blas_thread", spy)
    log = CarrierLog(condition=["a", "b"], run=[0, 0], seed=[0, 0], carrier=[1, 1],
        urgency0=[5, 5], order_time=[0.0, 0.0], pickup_time=[1.0, 1.0],
        delivery_time=[20.0, 12.0], robot=[0, 0])  # fmt: skip
    summarize(log, n_resamples=20)
    events = EventTable(condition=["a"], seed=[0], run=[0], time=[1.0], kind=["select"],
        carrier=[1], robot=[0], value=[5.0], time_unit="tick")  # fmt: skip
    choice_statistics(events, n_resamples=20)
    assert len(inside) == 3  # two conditions' summaries, one condition's choices
    assert all(threads == [1] * len(threads) for threads in inside)
