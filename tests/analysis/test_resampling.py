"""Resampling whole runs: multiplicities, exact re-pooled percentiles, seeded streams."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from swarmtag.analysis import ConditionRuns, condition_seed_sequence, run_values
from swarmtag.analysis.resampling import (
    condition_generator,
    iter_multiplicities,
    multiplicities,
    resampled_percentiles,
)
from tests.io.strategies import carrier_logs


def test_multiplicities_count_draws():
    draws = np.array([[0, 0, 0], [2, 1, 0], [1, 1, 2]])
    assert multiplicities(draws, 3).tolist() == [[3, 0, 0], [1, 1, 1], [0, 2, 1]]


@given(st.integers(1, 50), st.integers(1, 40), st.integers(0, 2**32 - 1))
def test_multiplicity_rows_sum_to_the_number_of_runs(n_runs, n_resamples, seed):
    rng = np.random.default_rng(seed)
    counts = multiplicities(rng.integers(0, n_runs, size=(n_resamples, n_runs)), n_runs)
    assert counts.shape == (n_resamples, n_runs)
    assert (counts.sum(axis=1) == n_runs).all()


@given(carrier_logs(conditions=("c",), max_runs=8), st.integers(0, 2**32 - 1))
def test_repooled_percentiles_equal_numpy_on_concatenated_resamples(log, seed):
    """The fast weighted order statistics against the slow, obvious reference."""
    values = run_values(ConditionRuns.from_log(log, "c"))
    latencies = values.latencies
    rng = np.random.default_rng(seed)
    draws = rng.integers(0, values.n_runs, size=(30, values.n_runs))
    percentiles = [95, 0, 2.5, 50, 97.5, 100, 33.3]
    fast = resampled_percentiles(
        latencies.values, latencies.runs, multiplicities(draws, values.n_runs), percentiles
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
