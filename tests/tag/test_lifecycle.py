"""Who may change what (SPEC §2.2): every (role, from, to) combination."""

from __future__ import annotations

import itertools

import pytest
from hypothesis import given

from swarmtag.errors import FieldRangeError, IllegalTransition, RoleNotAllowed
from swarmtag.tag import Change, Role, TagState, TagStatus, apply_change
from tests.strategies import changes, tag_states

A, P, D = TagStatus.AWAITING_PICKUP, TagStatus.PICKED_UP, TagStatus.IDLE  # D: done (idle)


def _state(status: TagStatus) -> TagState:
    return TagState(urgency=4, status=status, destination=2, marker=7)


def test_robot_transitions_are_exactly_lift_and_release():
    allowed = set()
    for old, new in itertools.product(TagStatus, TagStatus):
        try:
            result = apply_change(_state(old), Change(status=new), Role.ROBOT)
        except IllegalTransition:
            continue
        assert result == TagState(urgency=4, status=new, destination=2, marker=7)
        allowed.add((old, new))
    assert allowed == {(A, P), (P, D)}


@pytest.mark.parametrize(("old", "new"), [(D, A), (D, P), (A, D), (P, A), (A, A), (D, D)])
def test_robot_other_transitions_refused_with_clear_message(old, new):
    with pytest.raises(IllegalTransition, match=f"from {old.name} to {new.name}"):
        apply_change(_state(old), Change(status=new), Role.ROBOT)


@pytest.mark.parametrize(
    ("change", "words"),
    [
        (Change(urgency=9), "urgency"),
        (Change(destination=3), "destination"),
        (Change(urgency=0, status=P), "urgency"),
        (Change(urgency=1, destination=1), "urgency or destination"),
    ],
)
def test_robot_may_not_change_urgency_or_destination(change, words):
    with pytest.raises(RoleNotAllowed, match=words):
        apply_change(_state(A), change, Role.ROBOT)


@pytest.mark.parametrize(("old", "new"), list(itertools.product(TagStatus, TagStatus)))
def test_operator_may_set_any_status(old, new):
    assert apply_change(_state(old), Change(status=new), Role.OPERATOR).status is new


@given(tag_states, changes)
def test_operator_change_sets_exactly_the_given_fields(state, change):
    result = apply_change(state, change, Role.OPERATOR)
    assert result.marker == state.marker
    for name in ("urgency", "status", "destination"):
        wanted = getattr(change, name)
        assert getattr(result, name) == (getattr(state, name) if wanted is None else wanted)


def test_out_of_range_values_refused_by_the_state():
    with pytest.raises(FieldRangeError, match="urgency"):
        apply_change(_state(A), Change(urgency=10), Role.OPERATOR)
