"""One robot's choice from a Candidate list, for the behaviour-tree controller."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from swarmtag.errors import PolicyError
from swarmtag.policy import Candidate, Proximity, Urgency, Weighted, choose

NEAR_LOW = Candidate(marker=10, urgency=1, distance=0.9)  # u_d = 6.75
FAR_HIGH = Candidate(marker=11, urgency=9, distance=2.7)  # u_d = 2.25


def test_proximity_and_urgency_disagree():
    # proximity: 6.75 > 2.25; urgency 0.7: 1 * 7.45 = 7.45 < 9 * 2.95 = 26.55.
    assert choose(Proximity(), [NEAR_LOW, FAR_HIGH]) is NEAR_LOW
    assert choose(Urgency(alpha=0.7), [NEAR_LOW, FAR_HIGH]) is FAR_HIGH
    assert choose(Urgency(alpha=0.7), [FAR_HIGH, NEAR_LOW]) is FAR_HIGH


def test_empty_list_gives_none():
    assert choose(Urgency(alpha=0.7), []) is None
    assert choose(Proximity(), ()) is None


def test_single_candidate_is_chosen_whatever_its_score():
    lonely = Candidate(marker=3, urgency=0, distance=50.0)
    for policy in (Proximity(), Urgency(alpha=0.7), Weighted(w=1.0)):
        assert choose(policy, [lonely]) is lonely


def test_ties_follow_the_same_rule_as_select():
    a = Candidate(marker=8, urgency=0, distance=1.0)
    b = Candidate(marker=2, urgency=0, distance=1.0)
    c = Candidate(marker=1, urgency=0, distance=2.0)
    # all score 0 under urgency: nearest (a, b at 1.0 m), then the smaller marker (b).
    assert choose(Urgency(alpha=0.7), [a, b, c]) is b


def test_choose_calls_select(monkeypatch):
    # The formulas and the tie rule exist once: choose must delegate to select.
    import swarmtag.policy._choose as choose_module

    calls = []

    def fake_select(policy, **arrays):
        calls.append(arrays)
        return np.asarray(1, dtype=np.intp)

    monkeypatch.setattr(choose_module, "select", fake_select)
    assert choose(Proximity(), [NEAR_LOW, FAR_HIGH]) is FAR_HIGH
    assert len(calls) == 1
    np.testing.assert_array_equal(calls[0]["marker"], [10, 11])
    np.testing.assert_array_equal(calls[0]["urgency"], [1, 9])
    np.testing.assert_array_equal(calls[0]["distance"], [0.9, 2.7])


def test_candidate_is_a_frozen_record():
    with pytest.raises(dataclasses.FrozenInstanceError):
        NEAR_LOW.urgency = 5  # type: ignore[misc]
    assert Candidate(1, 2, 3.0) == Candidate(marker=1, urgency=2, distance=3.0)


def test_candidate_accepts_numpy_numbers():
    candidate = Candidate(marker=np.int64(3), urgency=np.uint8(9), distance=np.float32(1.5))
    assert choose(Urgency(alpha=0.7), [candidate]) is candidate


@pytest.mark.parametrize(
    ("fields", "name"),
    [
        ({"marker": 1.5, "urgency": 1, "distance": 1.0}, "marker"),
        ({"marker": True, "urgency": 1, "distance": 1.0}, "marker"),
        ({"marker": 1, "urgency": 1.0, "distance": 1.0}, "urgency"),
        ({"marker": 1, "urgency": "9", "distance": 1.0}, "urgency"),
        ({"marker": 1, "urgency": 1, "distance": "near"}, "distance"),
        ({"marker": 1, "urgency": 1, "distance": None}, "distance"),
    ],
)
def test_candidate_refuses_wrong_types(fields, name):
    with pytest.raises(PolicyError, match=f"{name}: "):
        Candidate(**fields)


@pytest.mark.parametrize(
    ("candidate", "name"),
    [
        (Candidate(marker=1, urgency=10, distance=1.0), "urgency"),
        (Candidate(marker=1, urgency=-1, distance=1.0), "urgency"),
        (Candidate(marker=1, urgency=1, distance=-1.0), "distance"),
        (Candidate(marker=1, urgency=1, distance=math.nan), "distance"),
        (Candidate(marker=2**70, urgency=1, distance=1.0), "marker"),
    ],
)
def test_choose_refuses_values_out_of_range(candidate, name):
    with pytest.raises(PolicyError, match=f"{name}: "):
        choose(Proximity(), [candidate])
