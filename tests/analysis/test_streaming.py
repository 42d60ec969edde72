"""Streaming bootstrap: chunks that do not change the numbers, and memory refused up front.

The resamples are drawn and evaluated in chunks of ``CHUNK_ELEMENTS``. The
draws are the same whatever the chunking (one continuing int64 stream), and
so is every figure computed without BLAS (the re-pooled and Kaplan-Meier
percentiles, the latency curve). The figures that sum over runs use a BLAS
matrix product whose last bits can depend on the rows per product: they are
pinned to within a few ulps here, and the chunk budget itself is pinned,
since changing it would change those bits.
"""

from __future__ import annotations

import functools
import importlib
import tracemalloc
from pathlib import Path

import numpy as np
import pytest

from swarmtag._resources import MEMORY_LIMIT_VARIABLE
from swarmtag._threads import default_threads
from swarmtag.analysis import (
    ConditionRuns,
    choice_statistics,
    condition_statistics,
    split_conditions,
    summarize,
)
from swarmtag.analysis import bootstrap as bootstrap_module
from swarmtag.analysis import summary as summary_module
from swarmtag.analysis.resampling import (
    CHUNK_ELEMENTS,
    PER_VALUE_ARRAYS,
    THREAD_BYTES,
    WORKING_ARRAYS,
    bootstrap_memory,
    condition_generator,
    iter_multiplicities,
    multiplicities,
    one_blas_thread,
)
from swarmtag.data import example_trial_path
from swarmtag.errors import ResourceError
from swarmtag.io import CarrierLog, EventTable, read_event_log
from tests.io.strategies import log_from_rows

EXACT = ("p95_latency", "p95_latency_censored", "km_p95_latency")
"""Figures computed without BLAS: bit for bit the same whatever the chunking."""
SUMMED = ("mean_latency", "throughput", "pa", "deliveries_per_run", "mean_latency_censored")
"""Figures from sums over runs (a BLAS product): the same to within a few ulps."""


def _example_log() -> CarrierLog:
    return read_event_log(Path(example_trial_path()))


def _mixed_log(n_runs: int, seed: int) -> CarrierLog:
    """Runs of 1-5 carriers with undelivered ones, ties and ``urgency_end``."""
    rng = np.random.default_rng(seed)
    rows, urgency_end = [], []
    for run in range(n_runs):
        for carrier in range(int(rng.integers(1, 6))):
            delivered = rng.random() < 0.8
            delivery = float(rng.integers(1, 40)) if delivered else None
            rows.append(
                ("c", run, carrier, int(rng.integers(0, 10)), -float(rng.integers(0, 9)), delivery)
            )
            urgency_end.append(int(rng.integers(0, 10)))
    ends = [50.0] * len(rows)
    return log_from_rows(rows, run_end=ends, urgency_end=urgency_end)


@pytest.mark.parametrize("n_runs", [1, 2, 12, 13, 257])
@pytest.mark.parametrize("seed", [0, 5])
def test_chunked_draws_equal_one_unchunked_draw(n_runs, seed):
    n_resamples = 41
    rng = condition_generator(seed, "c")
    whole = multiplicities(rng.integers(0, n_runs, size=(n_resamples, n_runs)), n_runs)
    for budget in (1, n_runs, 3 * n_runs + 1, 10**9):
        chunked_rng = condition_generator(seed, "c")
        chunks = list(
            iter_multiplicities(
                chunked_rng, n_runs, n_resamples, width=n_runs, chunk_elements=budget
            )
        )
        expected_rows = max(1, min(n_resamples, budget // n_runs))
        assert len(chunks[0]) == expected_rows
        np.testing.assert_array_equal(np.vstack(chunks), whole)
        # The generator ends where the one big draw left it: the stream continues exactly.
        assert chunked_rng.bit_generator.state == rng.bit_generator.state


@pytest.mark.parametrize("dtype", [np.int64, np.uint64, np.int32, np.uint32])
def test_bounded_integers_of_32_and_64_bits_are_one_stream(dtype):
    # The property the chunking relies on (numpy's 8- and 16-bit paths buffer within a call).
    for bound in (2, 3, 12, 1000):
        whole = np.random.default_rng(9).integers(0, bound, size=(7, 5), dtype=dtype)
        rng = np.random.default_rng(9)
        rows = [rng.integers(0, bound, size=(1, 5), dtype=dtype) for _ in range(7)]
        np.testing.assert_array_equal(np.vstack(rows), whole)


@pytest.mark.parametrize(("n_runs", "seed", "n_resamples"), [(1, 0, 30), (9, 1, 57), (24, 4, 40)])
def test_tiny_chunks_give_the_same_bootstrap(n_runs, seed, n_resamples):
    runs = ConditionRuns.from_log(_mixed_log(n_runs, seed), "c")
    whole = condition_statistics(runs, n_resamples=n_resamples, seed=seed, _chunk_elements=10**9)
    width = len(runs.carrier)
    for budget in (1, width, 2 * width + 1):
        chunked = condition_statistics(
            runs, n_resamples=n_resamples, seed=seed, _chunk_elements=budget
        )
        for metric in EXACT:
            np.testing.assert_array_equal(
                chunked.estimate(metric).bootstrap_distribution,
                whole.estimate(metric).bootstrap_distribution,
                err_msg=metric,
            )
            assert (
                chunked.estimate(metric).confidence_interval
                == whole.estimate(metric).confidence_interval
            )
        for bound in ("low", "high"):
            np.testing.assert_array_equal(
                getattr(chunked.latency_curve, bound), getattr(whole.latency_curve, bound)
            )
        for metric in (*SUMMED, "pa_at_delivery"):
            np.testing.assert_allclose(
                chunked.estimate(metric).bootstrap_distribution,
                whole.estimate(metric).bootstrap_distribution,
                rtol=1e-14,
                atol=0,
                err_msg=metric,
            )
        np.testing.assert_allclose(chunked.pa_curve.low, whole.pa_curve.low, rtol=1e-14, atol=0)


def test_the_chunk_budget_is_pinned():
    # The chunks' sizes reach the last bits of the summed figures (BLAS): keep them as they are.
    assert CHUNK_ELEMENTS == 1 << 22
    rng = condition_generator(0, "c")
    sizes = [len(w) for w in iter_multiplicities(rng, 12, 110_000, width=84)]
    assert sizes == [49_932, 49_932, 10_136]


def test_the_bootstrap_values_are_separate_read_only_arrays():
    runs = ConditionRuns.from_log(_mixed_log(6, 2), "c")
    statistics = condition_statistics(runs, n_resamples=50)
    arrays = [statistics.estimate(m).bootstrap_distribution for m in statistics.metrics]
    for array in arrays:
        assert array.flags.owndata
        assert array.flags.c_contiguous
        assert not array.flags.writeable


def test_the_estimate_follows_its_formula():
    n, chunk = 1_000_000, min(1_000_000 * 84, max(CHUNK_ELEMENTS, 84))

    def fixed(conditions: int, width: int) -> int:
        return 8 * PER_VALUE_ARRAYS * conditions * width

    # 2 conditions of 9 metrics, max(41 curve points, 1 comparison x 9) + 3 temporaries.
    expected = 8 * (n * (2 * 9 + 41 + 3) + WORKING_ARRAYS * chunk) + fixed(2, 84)
    assert bootstrap_memory(n, conditions=2, width=84) == expected
    # 6 conditions: the 5 comparisons' 45 differences outweigh the 41 curve points.
    assert bootstrap_memory(n, conditions=6, width=84) == (
        8 * (n * (6 * 9 + 45 + 3) + WORKING_ARRAYS * chunk) + fixed(6, 84)
    )
    # 2 conditions at once on 2 threads: two conditions' curve values, temporaries and chunks.
    assert bootstrap_memory(n, conditions=2, width=84, threads=2) == (
        8 * (n * (2 * 9 + 2 * 41 + 2 * 3) + 2 * WORKING_ARRAYS * chunk)
        + fixed(2, 84)
        + THREAD_BYTES
    )
    # Choice statistics: 4 means per condition, no curves, no comparisons; tiny B, tiny chunk.
    choices = bootstrap_memory(10, conditions=3, width=5, metrics=4, curve_points=0, comparisons=0)
    assert choices == 8 * (10 * (12 + 3) + WORKING_ARRAYS * 50) + fixed(3, 5)


@pytest.mark.parametrize("n_resamples", [10, 6000, 20_000])
def test_the_estimate_bounds_what_summarize_allocates(n_resamples):
    importlib.import_module("scipy.stats")  # a library, not counted by the estimate
    with one_blas_thread():  # nor is finding the BLAS libraries, once a process
        pass
    log = _example_log()
    tracemalloc.start()
    try:
        summarize(log, n_resamples=n_resamples)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    threads = min(2, default_threads())  # summarize's: one a condition, at most one a core
    estimate = bootstrap_memory(n_resamples, conditions=2, width=84, threads=threads)
    assert peak <= estimate
    if n_resamples > 1000:
        assert peak >= estimate / 3  # and not a wild overestimate


@pytest.mark.parametrize("n_resamples", [1_000_000, 10**12])
def test_summarize_refuses_what_cannot_fit_before_drawing(monkeypatch, n_resamples):
    monkeypatch.setenv("SWARMTAG_MEMORY_LIMIT", "10MiB")

    def never(*args: object, **kwargs: object) -> None:
        raise AssertionError("nothing may be drawn for a refused request")

    monkeypatch.setattr(bootstrap_module, "_replicates", never)
    with pytest.raises(ResourceError) as refused:
        summarize(_example_log(), n_resamples=n_resamples)
    message = str(refused.value)
    assert message.startswith(f"--resamples {n_resamples} over 2 conditions needs about ")
    assert "10.0 MiB is available" in message
    assert "SWARMTAG_MEMORY_LIMIT" in message


def test_an_absurd_request_is_refused_on_any_machine():
    with pytest.raises(ResourceError, match=r"--resamples 1000000000000 over 2 conditions"):
        summarize(_example_log(), n_resamples=10**12)


def test_condition_statistics_refuses_too(monkeypatch):
    monkeypatch.setenv("SWARMTAG_MEMORY_LIMIT", "1MiB")
    runs = split_conditions(_example_log())["proximity"]
    with pytest.raises(ResourceError, match=r"--resamples 100000 over 1 condition needs"):
        condition_statistics(runs, n_resamples=100_000)
    monkeypatch.setenv("SWARMTAG_MEMORY_LIMIT", "64MiB")
    assert condition_statistics(runs, n_resamples=100).n_resamples == 100


def test_choice_statistics_refuses_too(monkeypatch):
    table = EventTable(
        condition=["a", "b"],
        seed=[0, 0],
        run=[0, 0],
        time=[1.0, 1.0],
        kind=["select", "select"],
        carrier=[1, 1],
        robot=[0, 0],
        value=[0.0, 0.0],
    )
    monkeypatch.setenv("SWARMTAG_MEMORY_LIMIT", "1MiB")
    with pytest.raises(ResourceError, match=r"--resamples 1000000 over 2 conditions needs"):
        choice_statistics(table, n_resamples=1_000_000)
    assert len(choice_statistics(table, n_resamples=100)) == 2


def test_an_interrupt_between_chunks_is_not_swallowed(monkeypatch):
    calls = []
    original = bootstrap_module.km_resampled_quantiles

    def interrupted(*args: object, **kwargs: object) -> object:
        calls.append(1)
        if len(calls) == 2:
            raise KeyboardInterrupt
        return original(*args, **kwargs)

    monkeypatch.setattr(bootstrap_module, "km_resampled_quantiles", interrupted)
    runs = ConditionRuns.from_log(_mixed_log(5, 0), "c")
    with pytest.raises(KeyboardInterrupt):
        condition_statistics(runs, n_resamples=100, _chunk_elements=len(runs.carrier) * 10)
    assert len(calls) == 2  # stopped at the chunk it was interrupted in


def test_conditions_share_the_threads_that_the_memory_holds(monkeypatch):
    monkeypatch.setenv("SWARMTAG_THREADS", "4")
    need = functools.partial(bootstrap_memory, 20_000, conditions=6, width=84)
    for limit, threads in [(need(threads=5), 4), (need(threads=3), 3), (need(threads=2) - 1, 1)]:
        monkeypatch.setenv(MEMORY_LIMIT_VARIABLE, str(limit))
        assert summary_module._threads(20_000, conditions=6, width=84) == threads
    monkeypatch.setenv(MEMORY_LIMIT_VARIABLE, str(need() - 1))
    with pytest.raises(ResourceError, match="over 6 conditions needs about"):
        summary_module._threads(20_000, conditions=6, width=84)
