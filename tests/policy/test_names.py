"""Condition names (SPEC §8.1) parse back into policies and round-trip."""

from __future__ import annotations

import pytest
from hypothesis import given
from hypothesis import strategies as st

from swarmtag.errors import PolicyError
from swarmtag.policy import Proximity, Urgency, Weighted, parse_policy

ACCEPTED = "accepted forms: 'proximity', 'urgency:alpha=A'"


@pytest.mark.parametrize(
    ("text", "policy"),
    [
        ("proximity", Proximity()),
        ("urgency:alpha=0.7", Urgency(alpha=0.7)),
        ("weighted:w=0.3", Weighted(w=0.3)),
        # forgiving spellings
        ("urgency:alpha=3", Urgency(alpha=3.0)),
        ("  proximity\n", Proximity()),
        ("PROXIMITY", Proximity()),
        ("Urgency:alpha=0.7", Urgency(alpha=0.7)),
        ("urgency:ALPHA=0.7", Urgency(alpha=0.7)),
        (" urgency : alpha = 0.7 ", Urgency(alpha=0.7)),
        ("weighted:w=1", Weighted(w=1.0)),
        ("weighted:w=0", Weighted(w=0.0)),
        ("weighted:w=.5", Weighted(w=0.5)),
        ("urgency:alpha=1E-5", Urgency(alpha=1e-05)),
        ("urgency:alpha=+2", Urgency(alpha=2.0)),
    ],
)
def test_parses_canonical_names_and_forgiving_spellings(text, policy):
    assert parse_policy(text) == policy


@pytest.mark.parametrize(
    "policy",
    [
        Proximity(),
        Urgency(alpha=0.1),
        Urgency(alpha=0.7),
        Urgency(alpha=3),
        Urgency(alpha=1e-05),
        Urgency(alpha=1e16),
        Urgency(alpha=5e-324),
        Urgency(alpha=0.1 + 0.2),
        Weighted(w=0.0),
        Weighted(w=0.1),
        Weighted(w=1.0),
        Weighted(w=1e-05),
    ],
)
def test_round_trip_through_repr_forms(policy):
    assert parse_policy(policy.name) == policy
    assert parse_policy(policy.name).name == policy.name


@given(st.floats(min_value=0, max_value=1e300, exclude_min=True))
def test_every_urgency_name_round_trips(alpha):
    policy = Urgency(alpha=alpha)
    assert parse_policy(policy.name) == policy


@given(st.floats(min_value=0, max_value=1))
def test_every_weighted_name_round_trips(w):
    policy = Weighted(w=w)
    assert parse_policy(policy.name) == policy


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("", "cannot read ''"),
        ("   ", "cannot read"),
        ("nearest", "unknown policy 'nearest'"),
        ("urgency", "urgency takes one parameter alpha"),
        ("urgency:w=0.3", "urgency takes one parameter alpha"),
        ("weighted:alpha=0.3", "weighted takes one parameter w"),
        ("proximity:alpha=1", "proximity takes no parameter"),
        ("urgency:alpha=", "cannot read"),
        ("urgency:alpha=abc", "alpha: 'abc'"),
        ("urgency:alpha=nan", "alpha: 'nan' .* is not a decimal number"),
        ("urgency:alpha=inf", "alpha: 'inf'"),
        ("urgency:alpha=1_000", "alpha: '1_000'"),
        ("urgency:alpha=0.7:w=0.3", "alpha: '0.7:w=0.3'"),
        ("urgency alpha=0.7", "cannot read"),
        ("urgency:alpha=0.7,", "alpha: '0.7,'"),
    ],
)
def test_rejects_other_text_naming_it_and_listing_accepted_forms(text, message):
    with pytest.raises(PolicyError, match=message) as info:
        parse_policy(text)
    assert ACCEPTED in str(info.value)


@pytest.mark.parametrize(
    ("text", "message"),
    [
        (
            "urgency:alpha=0",
            r"alpha: 0.0 must be a finite number > 0 \(in condition name 'urgency:",
        ),
        ("urgency:alpha=-1", r"alpha: -1.0 must be a finite number > 0"),
        ("weighted:w=1.5", r"w: 1.5 must be a number with 0 <= w <= 1 \(in condition name"),
        ("urgency:alpha=1e999", r"alpha: inf must be a finite number > 0"),
    ],
)
def test_rejects_parameters_out_of_range(text, message):
    with pytest.raises(PolicyError, match=message):
        parse_policy(text)


@pytest.mark.parametrize("value", [None, 0.7, b"proximity", Proximity()])
def test_rejects_non_strings(value):
    with pytest.raises(PolicyError, match=r"condition name: .* is not a string"):
        parse_policy(value)
