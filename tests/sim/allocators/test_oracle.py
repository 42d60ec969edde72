"""The central assignment: the optimum of small cases, found by trying every assignment."""

from __future__ import annotations

import itertools

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from swarmtag.sim.allocators import assign
from swarmtag.sim.allocators.oracle import TIE_PER_METRE


def brute_force(score, distance, allowed) -> tuple[int, float]:
    """The most pairs, then the largest total, over every partial assignment of allowed pairs."""
    robots, carriers = allowed.shape
    best = (0, 0.0)
    slots = list(range(carriers)) + [-1] * robots  # -1: the robot gets nothing
    for pick in set(itertools.permutations(slots, robots)):
        used = [c for c in pick if c >= 0]
        if len(used) != len(set(used)):
            continue
        if any(c >= 0 and not allowed[r, c] for r, c in enumerate(pick)):
            continue
        best = max(best, (len(used), total(pick, score, distance)))
    return best


def total(choice, score, distance) -> float:
    return sum(score[r, c] - TIE_PER_METRE * distance[r, c] for r, c in enumerate(choice) if c >= 0)


@settings(max_examples=150, deadline=None)
@given(
    robots=st.integers(1, 4),
    carriers=st.integers(1, 4),
    seed=st.integers(0, 2**32 - 1),
    forbid=st.floats(0.0, 0.7),
)
def test_the_assignment_is_a_largest_total(robots, carriers, seed, forbid):
    rng = np.random.default_rng(seed)
    score = rng.integers(0, 10, size=(robots, carriers)) * rng.uniform(0.7, 9.7, (robots, carriers))
    distance = rng.uniform(0.0, 8.0, (robots, carriers))
    allowed = rng.random((robots, carriers)) >= forbid
    choice = assign(score, distance, allowed)
    assigned = choice[choice >= 0]
    assert len(set(assigned.tolist())) == len(assigned)  # one robot per carrier
    assert all(allowed[r, c] for r, c in enumerate(choice) if c >= 0)
    pairs, best = brute_force(score, distance, allowed)
    assert len(assigned) == pairs
    assert total(choice, score, distance) == pytest.approx(best)


def test_equal_scores_go_to_the_shorter_total_distance():
    score = np.full((2, 2), 5.0)
    distance = np.array([[1.0, 4.0], [1.5, 2.0]])
    assert assign(score, distance, np.ones((2, 2), bool)).tolist() == [0, 1]


def test_every_robot_that_can_be_served_is_served():
    # robot 0 can only take carrier 0; serving both beats robot 1's better score there
    score = np.array([[1.0, 0.0], [9.0, 0.0]])
    allowed = np.array([[True, False], [True, True]])
    assert assign(score, np.zeros((2, 2)), allowed).tolist() == [0, 1]


def test_nothing_allowed_assigns_nothing():
    assert assign(np.ones((2, 3)), np.ones((2, 3)), np.zeros((2, 3), bool)).tolist() == [-1, -1]
