"""Exact percentiles: per-run segments and numpy's interpolation, bit for bit."""

from __future__ import annotations

import numpy as np
from hypothesis import given
from hypothesis import strategies as st
from hypothesis.extra import numpy as hnp

from swarmtag.analysis.latency import interpolation_points, lerp, segment_percentile

finite = st.floats(-1e6, 1e6, allow_nan=False, allow_infinity=False)
percent = st.one_of(st.sampled_from([0, 2.5, 5, 50, 95, 97.5, 100]), st.floats(0, 100))


@given(hnp.arrays(np.float64, st.integers(1, 40), elements=finite), percent)
def test_matches_numpy_percentile_exactly(sample, q):
    values = np.sort(sample)
    lower, upper, gamma = interpolation_points(np.array([values.size]), q)
    ours = lerp(values[lower], values[upper], gamma)[0]
    assert ours == np.percentile(sample, q)


@given(st.lists(st.lists(finite, max_size=8), min_size=1, max_size=6), percent)
def test_segments_match_numpy_per_segment(segments, q):
    counts = np.array([len(segment) for segment in segments], dtype=np.int64)
    starts = np.cumsum(counts) - counts
    values = np.concatenate([np.sort(segment) for segment in segments] + [np.empty(0)])
    result = segment_percentile(values, starts, counts, q)
    for segment, got in zip(segments, result, strict=True):
        if segment:
            assert got == np.percentile(segment, q)
        else:
            assert np.isnan(got)


def test_interpolation_at_the_top_and_between():
    lower, upper, gamma = interpolation_points(np.array([1, 5, 7]), 95)
    # n = 1: position 0; n = 5: 3.8 -> between 3 and 4; n = 7: 5.7 -> between 5 and 6.
    assert lower.tolist() == [0, 3, 5]
    assert upper.tolist() == [0, 4, 6]
    assert np.allclose(gamma, [0.0, 0.8, 0.7])


@given(
    st.lists(st.integers(1, 10**6), min_size=1, max_size=20),
    st.lists(percent, min_size=1, max_size=25),
)
def test_many_percentiles_at_once_are_each_percentile_alone(counts, percentiles):
    # Broadcasting sizes against percentiles does element by element what one percentile does.
    sizes = np.asarray(counts, dtype=np.int64)
    lower, upper, gamma = interpolation_points(sizes[:, None], np.asarray(percentiles, float))
    for column, q in enumerate(percentiles):
        one = interpolation_points(sizes, q)
        np.testing.assert_array_equal(lower[:, column], one[0])
        np.testing.assert_array_equal(upper[:, column], one[1])
        np.testing.assert_array_equal(gamma[:, column], one[2])
