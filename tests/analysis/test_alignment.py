"""Priority alignment PA(p): the integer rule for k, the tie rules, and its extremes."""

from __future__ import annotations

import math
from fractions import Fraction

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from swarmtag.analysis import (
    CURVE_THRESHOLDS,
    PA_THRESHOLDS,
    ConditionRuns,
    alignment_k,
    priority_alignment,
)
from swarmtag.errors import StatisticsError
from tests.io.strategies import log_from_rows


def _runs(rows):
    return ConditionRuns.from_log(log_from_rows(rows), rows[0][0])


def test_k_uses_exact_integer_arithmetic():
    # Floating point: 35 % of 20 as 35 * 0.01 * 20 is 7.000000000000001, whose ceiling is 8;
    # exactly, 35 % of 20 carriers is 7 (and 70 % of 10 is 7, not 8).
    assert math.ceil(35 * 0.01 * 20) == 8
    assert alignment_k(35, [20]).tolist() == [7]
    assert alignment_k(70, [10]).tolist() == [7]
    assert alignment_k(15, [20]).tolist() == [3]
    assert alignment_k(5, [7, 20, 21, 1]).tolist() == [1, 1, 2, 1]
    assert alignment_k(50, [7, 1, 2, 3]).tolist() == [4, 1, 1, 2]
    assert alignment_k(0, [10]).tolist() == [1]  # never below one


@given(st.integers(0, 100), st.integers(1, 10_000))
def test_k_matches_exact_fractions(p, n):
    assert alignment_k(p, [n])[0] == max(1, math.ceil(Fraction(p * n, 100)))


@pytest.mark.parametrize("p", [-5, 101, 2.5, True, "10"])
def test_bad_threshold_is_refused(p):
    with pytest.raises(StatisticsError, match="PA threshold"):
        alignment_k(p, [5])


def test_urgency_ties_break_by_order_time_then_marker():
    # Three carriers of urgency 5: marker 7 ordered earliest, markers 2 and 4 at the same time.
    # Top ranking: 7 (order -9), then 2 (tie at -3, smaller marker), then 4.
    rows = [
        ("c", 0, 4, 5, -3.0, 1.0),
        ("c", 0, 2, 5, -3.0, 3.0),
        ("c", 0, 7, 5, -9.0, 2.0),
    ]
    # n = 3: p = 34 -> k = 2; p = 33 -> k = 1 (ceil(0.99)).
    # k = 1: top {7}, first {4} -> 0.   k = 2: top {7, 2}, first {4, 7} -> 1/2.
    assert priority_alignment(_runs(rows), [33, 34]).tolist() == [[0.0, 0.5]]


def test_delivery_ties_break_by_marker():
    # Marker 9 is the most urgent; markers 3 and 9 are delivered at the same time: 3 counts first.
    rows = [
        ("c", 0, 9, 9, 0.0, 5.0),
        ("c", 0, 3, 1, 0.0, 5.0),
        ("c", 0, 5, 0, 0.0, 8.0),
    ]
    # k = 1: top {9}, first {3} -> 0.   k = 2: top {9, 3}, first {3, 9} -> 1.
    assert priority_alignment(_runs(rows), [10, 50]).tolist() == [[0.0, 1.0]]


def test_fewer_deliveries_than_k():
    # n = 4, only the most urgent delivered: k = 2 -> first-k has one carrier, |∩| = 1 -> 1/2.
    rows = [
        ("c", 0, 1, 9, 0.0, 4.0),
        ("c", 0, 2, 8, 0.0, None),
        ("c", 0, 3, 7, 0.0, None),
        ("c", 0, 4, 6, 0.0, None),
    ]
    assert priority_alignment(_runs(rows), [25, 50, 100]).tolist() == [[1.0, 0.5, 0.25]]


def test_runs_are_rows_in_run_id_order():
    rows = [("c", 8, 1, 9, 0.0, 1.0), ("c", 8, 2, 0, 0.0, 2.0), ("c", 3, 1, 9, 0.0, 2.0)]
    rows.append(("c", 3, 2, 0, 0.0, 1.0))
    # Run 3 delivered the urgent one second (PA(50) = 0), run 8 first (PA(50) = 1).
    assert priority_alignment(_runs(rows), [50]).tolist() == [[0.0], [1.0]]


@st.composite
def ranked_runs(draw):
    """A run with a strict urgency ranking (the tie rules decide where urgencies tie)."""
    n = draw(st.integers(1, 30))
    markers = draw(st.lists(st.integers(0, 200), min_size=n, max_size=n, unique=True))
    urgencies = draw(st.lists(st.integers(0, 9), min_size=n, max_size=n))
    orders = draw(st.lists(st.integers(-5, 0), min_size=n, max_size=n))
    return sorted(zip(markers, urgencies, orders, strict=True), key=lambda c: (-c[1], c[2], c[0]))


@given(ranked_runs())
def test_pa_is_one_when_delivered_in_urgency_order(carriers):
    rows = [("c", 0, m, u, float(o), float(10 + i)) for i, (m, u, o) in enumerate(carriers)]
    pa = priority_alignment(_runs(rows), CURVE_THRESHOLDS)
    assert (pa == 1.0).all()


@given(ranked_runs())
def test_pa_is_zero_when_delivered_in_reverse_order(carriers):
    n = len(carriers)
    rows = [("c", 0, m, u, float(o), float(10 + n - i)) for i, (m, u, o) in enumerate(carriers)]
    pa = priority_alignment(_runs(rows), PA_THRESHOLDS)[0]
    for column, p in enumerate(PA_THRESHOLDS):
        k = int(alignment_k(p, [n])[0])
        # The first k delivered are the k least urgent: they meet the top k only if 2k > n.
        assert pa[column] == max(0, 2 * k - n) / k
        if 2 * k <= n:
            assert pa[column] == 0.0


@given(ranked_runs(), st.integers(0, 30))
def test_only_the_most_urgent_delivered(carriers, delivered):
    n = len(carriers)
    delivered = min(delivered, n)
    rows = [
        ("c", 0, m, u, float(o), float(10 + i) if i < delivered else None)
        for i, (m, u, o) in enumerate(carriers)
    ]
    pa = priority_alignment(_runs(rows), CURVE_THRESHOLDS)[0]
    ks = [int(alignment_k(p, [n])[0]) for p in CURVE_THRESHOLDS]
    expected = [min(delivered, k) / k for k in ks]
    assert np.allclose(pa, expected, rtol=0, atol=1e-15)
