"""The proximity term u_d = 9 * (1 - min(d / 3.6, 1)) and its constants."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from swarmtag.errors import PolicyError
from swarmtag.policy import PROXIMITY_RANGE, URGENCY_SCALE, proximity_term


def test_constants_match_the_spec():
    assert PROXIMITY_RANGE == 3.6
    assert URGENCY_SCALE == 9.0


@pytest.mark.parametrize(
    ("distance", "expected"),
    [
        (0.0, 9.0),  # 9 * (1 - 0)
        (0, 9.0),  # an int distance is fine
        (0.9, 6.75),  # 0.9 / 3.6 = 0.25 exactly (3.6 is 4 * 0.9 in binary): 9 * 0.75
        (1.8, 4.5),  # 1.8 / 3.6 = 0.5 exactly: 9 * 0.5
        (2.7, 2.25),  # 2.7 / 3.6 rounds to 0.75: 9 * 0.25
        (3.6, 0.0),  # the edge of the range: 9 * (1 - 1)
        (5.0, 0.0),  # beyond 3.6 m: min(5 / 3.6, 1) = 1, clipped to 0
        (math.inf, 0.0),  # an unknown (infinite) distance scores 0
    ],
)
def test_hand_computed_values_are_exact(distance, expected):
    assert proximity_term(distance) == expected


def test_inexact_value_is_close():
    # 1.2 / 3.6 = 1/3: 9 * (1 - 1/3) = 6, one ulp off in floats.
    assert proximity_term(1.2) == pytest.approx(6.0)
    assert proximity_term(1.2) == 6.000000000000001


def test_scalar_gives_numpy_float_and_array_gives_array():
    scalar = proximity_term(1.8)
    assert type(scalar) is np.float64
    assert isinstance(scalar, float)
    array = proximity_term(np.array([[0.0, 1.8], [3.6, 5.0]]))
    assert isinstance(array, np.ndarray)
    assert array.dtype == np.float64
    np.testing.assert_array_equal(array, [[9.0, 4.5], [0.0, 0.0]])


def test_zero_dimensional_array_stays_an_array_and_list_becomes_one():
    zero_d = proximity_term(np.array(1.8))
    assert isinstance(zero_d, np.ndarray)
    assert zero_d.shape == ()
    listed = proximity_term([0.0, 1.8])
    assert isinstance(listed, np.ndarray)
    np.testing.assert_array_equal(listed, [9.0, 4.5])


def test_integer_arrays_are_converted_to_float():
    np.testing.assert_array_equal(proximity_term(np.array([0, 5])), [9.0, 0.0])


@given(st.lists(st.floats(min_value=0, max_value=10), min_size=1, max_size=20))
def test_array_form_is_bit_identical_to_the_plain_python_expression(distances):
    array = proximity_term(np.array(distances))
    for i, d in enumerate(distances):
        plain = 9.0 * (1.0 - min(d / 3.6, 1.0))  # the SPEC formula in plain Python floats
        assert array[i] == plain
        assert proximity_term(d) == plain


@pytest.mark.parametrize("bad", ["far", [1.0, "x"], None])
def test_non_numeric_distance_is_refused(bad):
    with pytest.raises(PolicyError, match="distance"):
        proximity_term(bad)
