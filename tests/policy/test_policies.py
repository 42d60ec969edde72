"""Scores of the three policies of SPEC §3.3, their parameters and names."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from swarmtag.errors import PolicyError
from swarmtag.policy import Policy, Proximity, Urgency, Weighted

# --- hand-computed scores ---------------------------------------------------------------


def test_proximity_ignores_urgency():
    # u_d(1.8) = 9 * (1 - 0.5) = 4.5 whatever the urgency.
    assert Proximity().score(0, 1.8) == 4.5
    assert Proximity().score(9, 1.8) == 4.5


def test_urgency_example_from_the_brief():
    # u = 9, d = 1.2: u_d = 9 * (1 - 1/3) = 6, score = 9 * (0.7 + 6.0) = 60.3.
    assert Urgency(alpha=0.7).score(9, 1.2) == pytest.approx(60.3)


@pytest.mark.parametrize(
    ("alpha", "urgency", "distance", "expected"),
    [
        (0.5, 4, 1.8, 20.0),  # 4 * (0.5 + 4.5) = 4 * 5 = 20, every step exact
        (3.0, 5, 1.8, 37.5),  # 5 * (3 + 4.5) = 37.5
        (2.25, 3, 0.0, 33.75),  # 3 * (2.25 + 9) = 3 * 11.25 = 33.75
        (2.25, 5, 1.8, 33.75),  # 5 * (2.25 + 4.5) = 5 * 6.75 = 33.75
        (0.5, 0, 0.0, 0.0),  # urgency 0 scores 0 however near
        (0.5, 6, 5.0, 3.0),  # beyond 3.6 m u_d = 0, score = u * alpha = 6 * 0.5
    ],
)
def test_urgency_exact_values(alpha, urgency, distance, expected):
    assert Urgency(alpha=alpha).score(urgency, distance) == expected


@pytest.mark.parametrize(
    ("w", "urgency", "distance", "expected"),
    [
        (0.5, 4, 1.8, 4.25),  # 0.5 * 4 + 0.5 * 4.5 = 2 + 2.25
        (0.0, 9, 1.8, 4.5),  # w = 0: u_d alone
        (1.0, 7, 1.8, 7.0),  # w = 1: urgency alone
        (0.25, 8, 0.0, 8.75),  # 0.25 * 8 + 0.75 * 9 = 2 + 6.75
    ],
)
def test_weighted_exact_values(w, urgency, distance, expected):
    assert Weighted(w=w).score(urgency, distance) == expected


def test_weighted_inexact_value():
    # 0.3 * 9 + 0.7 * 4.5 = 2.7 + 3.15 = 5.85 (not exact in binary floats).
    assert Weighted(w=0.3).score(9, 1.8) == pytest.approx(5.85)


def test_urgency_with_larger_alpha_gives_urgency_more_weight():
    # Near low-urgency (u=1, d=0.9, u_d=6.75) against far high-urgency (u=9, d=2.7, u_d=2.25):
    # the ratio far/near grows with alpha: 9 * (a + 2.25) / (a + 6.75) rises towards 9.
    ratios = [
        Urgency(alpha=a).score(9, 2.7) / Urgency(alpha=a).score(1, 0.9) for a in (0.3, 0.7, 3, 9)
    ]
    assert ratios == sorted(ratios)


# --- scalars and arrays ----------------------------------------------------------------


@pytest.mark.parametrize("policy", [Proximity(), Urgency(alpha=0.7), Weighted(w=0.3)])
def test_scores_broadcast_and_match_scalars_bit_for_bit(policy):
    urgency = np.array([[0], [4], [9]])  # (3, 1)
    distance = np.array([0.0, 1.2, 2.5, 3.6, 7.0])  # (5,)
    scores = policy.score(urgency, distance)
    assert scores.shape == (3, 5)
    assert scores.dtype == np.float64
    for i, u in enumerate(urgency[:, 0]):
        for j, d in enumerate(distance):
            assert scores[i, j] == policy.score(int(u), float(d))


@pytest.mark.parametrize("policy", [Proximity(), Urgency(alpha=0.7), Weighted(w=0.3)])
def test_scalar_inputs_give_numpy_float(policy):
    assert type(policy.score(5, 1.0)) is np.float64
    zero_d = policy.score(np.array(5), 1.0)
    assert isinstance(zero_d, np.ndarray)
    assert zero_d.shape == ()


def test_proximity_score_has_the_broadcast_shape_even_though_urgency_is_unused():
    assert Proximity().score(np.zeros((2, 3)), 1.8).shape == (2, 3)


def test_score_refuses_shapes_that_do_not_broadcast():
    with pytest.raises(PolicyError, match=r"urgency and distance: shapes \(3,\) and \(4,\)"):
        Urgency(alpha=0.7).score(np.zeros(3), np.zeros(4))


def test_score_refuses_non_numbers():
    with pytest.raises(PolicyError, match="urgency"):
        Urgency(alpha=0.7).score("high", 1.0)


# --- parameters -----------------------------------------------------------------------


@pytest.mark.parametrize("alpha", [0, 0.0, -1.0, -0.0, math.nan, math.inf, -math.inf])
def test_urgency_refuses_alpha_that_is_not_finite_and_positive(alpha):
    with pytest.raises(PolicyError, match=r"alpha: .* must be a finite number > 0"):
        Urgency(alpha=alpha)


@pytest.mark.parametrize("alpha", ["0.7", None, True, 1j])
def test_urgency_refuses_alpha_that_is_not_a_real_number(alpha):
    with pytest.raises(PolicyError, match="alpha"):
        Urgency(alpha=alpha)


@pytest.mark.parametrize("w", [-0.1, 1.1, -1e-300, 1.0000000000000002, math.nan, math.inf])
def test_weighted_refuses_w_outside_unit_interval(w):
    with pytest.raises(PolicyError, match=r"w: .* must be a number with 0 <= w <= 1"):
        Weighted(w=w)


@pytest.mark.parametrize("w", ["0.3", None, False])
def test_weighted_refuses_w_that_is_not_a_real_number(w):
    with pytest.raises(PolicyError, match="w: "):
        Weighted(w=w)


def test_policy_error_is_a_value_error():
    with pytest.raises(ValueError, match="alpha"):
        Urgency(alpha=-1.0)


def test_parameters_are_stored_as_floats():
    assert type(Urgency(alpha=3).alpha) is float
    assert type(Urgency(alpha=np.float32(0.5)).alpha) is float
    assert type(Weighted(w=1).w) is float
    assert math.copysign(1.0, Weighted(w=-0.0).w) == 1.0  # -0.0 becomes 0.0


def test_boundary_parameters_are_accepted():
    assert Weighted(w=0).w == 0.0
    assert Weighted(w=1).w == 1.0
    assert Urgency(alpha=5e-324).alpha == 5e-324


# --- value objects and names ----------------------------------------------------------


@pytest.mark.parametrize(
    ("policy", "name"),
    [
        (Proximity(), "proximity"),
        (Urgency(alpha=0.7), "urgency:alpha=0.7"),
        (Urgency(alpha=3), "urgency:alpha=3.0"),
        (Urgency(alpha=9.0), "urgency:alpha=9.0"),
        (Urgency(alpha=1e-05), "urgency:alpha=1e-05"),
        (Urgency(alpha=0.1 + 0.2), "urgency:alpha=0.30000000000000004"),
        (Weighted(w=0.3), "weighted:w=0.3"),
        (Weighted(w=0), "weighted:w=0.0"),
        (Weighted(w=1), "weighted:w=1.0"),
    ],
)
def test_canonical_names(policy, name):
    assert policy.name == name
    assert str(policy) == name


def test_policies_are_equal_by_value_and_hashable():
    assert Urgency(alpha=3) == Urgency(alpha=3.0)
    assert hash(Urgency(alpha=3)) == hash(Urgency(alpha=3.0))
    assert Proximity() == Proximity()
    assert Urgency(alpha=0.7) != Weighted(w=0.7)
    assert Urgency(alpha=0.7) != Urgency(alpha=0.9)
    assert len({Proximity(), Proximity(), Urgency(alpha=1), Urgency(alpha=1.0)}) == 2


@pytest.mark.parametrize(
    ("policy", "field"), [(Urgency(alpha=0.7), "alpha"), (Weighted(w=0.3), "w")]
)
def test_parameters_cannot_be_changed(policy, field):
    with pytest.raises(dataclasses.FrozenInstanceError):
        setattr(policy, field, 1.0)


@pytest.mark.parametrize("policy", [Proximity(), Urgency(alpha=0.7), Weighted(w=0.3)])
def test_policies_are_slotted_and_take_no_new_attributes(policy):
    assert isinstance(policy, Policy)
    assert not hasattr(policy, "__dict__")
    # Python 3.11's frozen+slots dataclasses raise TypeError here instead of
    # FrozenInstanceError (a CPython quirk); either way nothing is set.
    with pytest.raises((AttributeError, TypeError)):
        policy.extra = 1.0
    assert not hasattr(policy, "extra")


def test_policy_base_is_abstract():
    with pytest.raises(TypeError, match="abstract"):
        Policy()  # type: ignore[abstract]
