"""kernel_score: the policies' formulas as one scalar function, bit for bit ``Policy.score``."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from swarmtag.errors import PolicyError
from swarmtag.policy import (
    EDF_KIND,
    PROXIMITY_KIND,
    URGENCY_KIND,
    WEIGHTED_KIND,
    Edf,
    Proximity,
    Urgency,
    Weighted,
    kernel_score,
)
from swarmtag.policy._kernel import kernel_score as plain_kernel_score

policies = st.one_of(
    st.just(Proximity()),
    st.just(Edf()),
    st.builds(Urgency, alpha=st.floats(1e-6, 1e6, allow_nan=False)),
    st.builds(Weighted, w=st.floats(0.0, 1.0)),
)
distances = st.floats(0.0, 50.0) | st.sampled_from([0.0, 1.8, 3.6, 3.6000000000000005, 7.2])


def test_kernel_forms():
    assert Proximity().kernel_form == (PROXIMITY_KIND, 0.0)
    assert Urgency(alpha=0.7).kernel_form == (URGENCY_KIND, 0.7)
    assert Weighted(w=0.3).kernel_form == (WEIGHTED_KIND, 0.3)
    assert Edf().kernel_form == (EDF_KIND, 0.0)


@given(policy=policies, urgency=st.integers(0, 9), distance=distances)
def test_kernel_score_is_the_score_bit_for_bit(policy, urgency, distance):
    kind, parameter = policy.kernel_form
    ours = kernel_score(kind, parameter, float(urgency), distance)
    theirs = float(policy.score(np.array([urgency]), np.array([distance]))[0])
    assert ours.hex() == theirs.hex()


def test_compiled_kernel_score_agrees():
    numba = pytest.importorskip("numba", reason="the compiled form needs the fast extra (numba)")
    compiled = numba.njit(plain_kernel_score)  # what the compiled simulator takes
    rng = np.random.default_rng(0)
    urgency = rng.integers(0, 10, 2000).astype(np.float64)
    distance = rng.random(2000) * 6.0
    for policy in (Proximity(), Urgency(alpha=0.7), Urgency(alpha=9.0), Weighted(w=0.3), Edf()):
        kind, parameter = policy.kernel_form
        expected = policy.score(urgency, distance)
        got = np.array(
            [compiled(kind, parameter, u, d) for u, d in zip(urgency, distance, strict=True)]
        )
        assert np.array_equal(got, expected)


@pytest.mark.parametrize(
    ("kind", "parameter", "urgency", "distance"),
    [(7, 0.5, 4.0, 1.0), (1, float("nan"), 4.0, 1.0), (1, 0.5, 10.0, 1.0), (1, 0.5, 4.0, -1.0),
     (1, 0.5, None, 1.0), (np.array([]), 0.5, 4.0, 1.0), (1, 0.5, 4.0, float("nan"))],
)  # fmt: skip
def test_the_public_kernel_score_checks_its_arguments(kind, parameter, urgency, distance):
    with pytest.raises(PolicyError):
        kernel_score(kind, parameter, urgency, distance)
