"""Batched selection: hand-built scenes, the tie rule, availability, shapes, validation."""

from __future__ import annotations

import math

import numpy as np
import pytest

from swarmtag.errors import PolicyError
from swarmtag.policy import Proximity, Urgency, Weighted, select

# A near low-urgency carrier and a far high-urgency one:
#   marker 10: u = 1, d = 0.9 -> u_d = 9 * (1 - 0.25) = 6.75
#   marker 11: u = 9, d = 2.7 -> u_d = 9 * (1 - 0.75) = 2.25
NEAR_LOW_FAR_HIGH = {"urgency": [1, 9], "distance": [0.9, 2.7], "marker": [10, 11]}


def pick(policy, **scene):
    index = select(policy, **scene)
    assert index.shape == ()
    assert index.dtype == np.intp
    return int(index)


def test_proximity_picks_the_near_carrier():
    # proximity scores 6.75 against 2.25.
    assert pick(Proximity(), **NEAR_LOW_FAR_HIGH) == 0


def test_urgency_picks_the_far_urgent_carrier():
    # alpha = 0.7: near 1 * (0.7 + 6.75) = 7.45, far 9 * (0.7 + 2.25) = 26.55.
    assert pick(Urgency(alpha=0.7), **NEAR_LOW_FAR_HIGH) == 1


# Where alpha decides:
#   marker 1: u = 3, d = 0.0 -> u_d = 9,   score 3 * (alpha + 9)   = 3 alpha + 27
#   marker 2: u = 5, d = 1.8 -> u_d = 4.5, score 5 * (alpha + 4.5) = 5 alpha + 22.5
# marker 1 wins iff 3 alpha + 27 > 5 alpha + 22.5, i.e. alpha < 2.25; at 2.25 both score 33.75.
ALPHA_DECIDES = {"urgency": [3, 5], "distance": [0.0, 1.8], "marker": [1, 2]}


@pytest.mark.parametrize(
    ("alpha", "expected"),
    [
        (0.7, 0),  # 3 * 9.7 = 29.1 > 5 * 5.2 = 26.0
        (2.0, 0),  # 3 * 11 = 33 > 5 * 6.5 = 32.5
        (2.5, 1),  # 3 * 11.5 = 34.5 < 5 * 7 = 35
        (3.0, 1),  # 3 * 12 = 36 < 5 * 7.5 = 37.5
        (9.0, 1),  # 3 * 18 = 54 < 5 * 13.5 = 67.5
    ],
)
def test_alpha_changes_the_choice(alpha, expected):
    assert pick(Urgency(alpha=alpha), **ALPHA_DECIDES) == expected


def test_exact_score_tie_at_the_crossover_goes_to_the_nearer_carrier():
    # alpha = 2.25: 3 * 11.25 = 33.75 = 5 * 6.75, both exact; marker 1 (d = 0) is nearer,
    # even when its marker id is the larger one.
    policy = Urgency(alpha=2.25)
    assert policy.score(3, 0.0) == policy.score(5, 1.8) == 33.75
    assert pick(policy, **ALPHA_DECIDES) == 0
    assert pick(policy, urgency=[3, 5], distance=[0.0, 1.8], marker=[99, 2]) == 0
    assert pick(policy, urgency=[5, 3], distance=[1.8, 0.0], marker=[2, 99]) == 1


def test_weighted_zero_chooses_like_proximity_and_one_by_urgency():
    scene = {"urgency": [1, 9, 5], "distance": [0.9, 2.7, 1.8], "marker": [1, 2, 3]}
    assert pick(Weighted(w=0.0), **scene) == pick(Proximity(), **scene) == 0
    assert pick(Weighted(w=1.0), **scene) == 1  # urgency 9 is the highest


def test_weighted_one_breaks_urgency_ties_by_distance():
    # w = 1 scores urgency alone: both urgent carriers score 9, the nearer (1.0 m) wins.
    scene = {"urgency": [9, 2, 9], "distance": [3.0, 0.1, 1.0], "marker": [1, 2, 3]}
    assert pick(Weighted(w=1.0), **scene) == 2


def test_weighted_in_between():
    # w = 0.5: near 0.5 * 1 + 0.5 * 6.75 = 3.875, far 0.5 * 9 + 0.5 * 2.25 = 5.625.
    assert pick(Weighted(w=0.5), **NEAR_LOW_FAR_HIGH) == 1
    # w = 0.3: near 0.3 + 0.7 * 6.75 = 5.025, far 2.7 + 0.7 * 2.25 = 4.275.
    assert pick(Weighted(w=0.3), **NEAR_LOW_FAR_HIGH) == 0


# --- the tie rule ---------------------------------------------------------------------


def test_all_zero_urgency_under_urgency_picks_the_nearest():
    # every score is 0 * (alpha + u_d) = 0: the tie goes to the smallest distance (1.0 m).
    scene = {"urgency": [0, 0, 0], "distance": [2.0, 1.0, 3.0], "marker": [1, 2, 3]}
    assert pick(Urgency(alpha=0.7), **scene) == 1


def test_equal_distance_and_score_picks_the_smaller_marker():
    scene = {"urgency": [4, 4, 4], "distance": [1.5, 1.5, 1.5], "marker": [9, 3, 7]}
    for policy in (Proximity(), Urgency(alpha=0.7), Weighted(w=0.3)):
        assert pick(policy, **scene) == 1


def test_proximity_beyond_range_picks_the_nearest():
    # every u_d is 0 beyond 3.6 m: the tie goes to the smallest distance, 3.9 m.
    scene = {"urgency": [0, 0, 0], "distance": [4.0, 3.9, 5.0], "marker": [1, 2, 3]}
    assert pick(Proximity(), **scene) == 1


def test_urgency_beyond_range_scores_urgency_times_alpha():
    # u_d = 0: scores 2 * 0.7 = 1.4 and 5 * 0.7 = 3.5; the farther, more urgent one wins.
    scene = {"urgency": [2, 5], "distance": [4.0, 10.0], "marker": [1, 2]}
    assert pick(Urgency(alpha=0.7), **scene) == 1


def test_infinite_distance_is_a_valid_unknown_distance():
    scene = {"urgency": [0, 0], "distance": [math.inf, 5.0], "marker": [1, 2]}
    assert pick(Proximity(), **scene) == 1


def test_proximity_ignores_urgency_entirely():
    scene = {"urgency": [0, 9], "distance": [1.0, 1.0], "marker": [5, 6]}
    assert pick(Proximity(), **scene) == 0  # same distance: the smaller marker, not urgency


# --- availability ---------------------------------------------------------------------


def test_unavailable_best_carrier_is_skipped():
    assert pick(Urgency(alpha=0.7), **NEAR_LOW_FAR_HIGH, available=[True, False]) == 0
    assert pick(Proximity(), **NEAR_LOW_FAR_HIGH, available=[False, True]) == 1


def test_nothing_available_gives_minus_one():
    assert pick(Urgency(alpha=0.7), **NEAR_LOW_FAR_HIGH, available=[False, False]) == -1


def test_no_carriers_gives_minus_one():
    assert pick(Proximity(), urgency=[], distance=[], marker=np.array([], dtype=int)) == -1
    empty = np.zeros((2, 3, 0))
    index = select(Proximity(), urgency=empty, distance=empty, marker=empty.astype(int))
    np.testing.assert_array_equal(index, np.full((2, 3), -1))


def test_unavailable_entries_are_not_used_for_ties():
    # the nearer carrier (marker 1) has the same score but is unavailable.
    scene = {"urgency": [0, 0, 0], "distance": [0.5, 1.0, 2.0], "marker": [1, 2, 3]}
    assert pick(Urgency(alpha=0.7), **scene, available=[False, True, True]) == 1


# --- batches and broadcasting ---------------------------------------------------------


def test_batch_of_runs_robots_carriers():
    # 2 runs x 2 robots x 3 carriers; robot distances differ, carrier urgencies are per run.
    urgency = np.array([[0, 9, 0], [5, 5, 5]])[:, None, :]  # (runs, 1, carriers)
    distance = np.array(
        [
            [[0.5, 3.0, 1.0], [2.0, 0.2, 0.3]],
            [[1.0, 0.5, 2.0], [0.4, 0.4, 0.1]],
        ]
    )
    marker = np.array([7, 8, 9])  # (carriers,)
    available = np.array(
        [
            [[True, True, True], [True, False, True]],
            [[False, False, False], [True, True, True]],
        ]
    )
    index = select(
        Urgency(alpha=0.7), urgency=urgency, distance=distance, marker=marker, available=available
    )
    assert index.shape == (2, 2)
    assert index.dtype == np.intp
    # run 0 robot 0: only carrier 1 has urgency > 0.
    # run 0 robot 1: carrier 1 unavailable, the rest score 0: nearest is carrier 2 (0.3 m).
    # run 1 robot 0: nothing available.
    # run 1 robot 1: equal urgency 5, nearest (0.1 m) scores highest: carrier 2.
    np.testing.assert_array_equal(index, [[1, 2], [-1, 2]])


def test_without_mask_every_robot_chooses():
    rng = np.random.default_rng(7)
    shape = (4, 3, 5)
    index = select(
        Weighted(w=0.3),
        urgency=rng.integers(0, 10, shape),
        distance=rng.uniform(0, 5, shape),
        marker=np.arange(5),
    )
    assert index.shape == (4, 3)
    assert ((index >= 0) & (index < 5)).all()


def test_accepts_numpy_integer_and_float_dtypes():
    scene = {
        "urgency": np.array([1, 9], dtype=np.uint8),
        "distance": np.array([0.9, 2.7], dtype=np.float32),
        "marker": np.array([10, 11], dtype=np.int16),
    }
    assert pick(Urgency(alpha=0.7), **scene) == 1


# --- validation -----------------------------------------------------------------------


def test_shape_mismatch_names_every_input_and_shape():
    with pytest.raises(PolicyError, match=r"urgency, distance, marker: shapes do not broadcast"):
        select(Proximity(), urgency=[1, 2, 3], distance=[1.0, 2.0], marker=[1, 2, 3])
    with pytest.raises(PolicyError, match=r"available \(4,\)"):
        select(
            Proximity(), urgency=[1, 2, 3], distance=[1.0, 2.0, 3.0], marker=[1, 2, 3],
            available=[True] * 4,
        )  # fmt: skip


def test_scalars_have_no_carrier_axis():
    with pytest.raises(PolicyError, match="last axis must index the carriers"):
        select(Proximity(), urgency=1, distance=1.0, marker=3)


@pytest.mark.parametrize("urgency", [[1, 10], [-1, 0], [math.nan, 1.0], [1, 9.5 + 1]])
def test_urgency_outside_zero_to_nine_is_refused(urgency):
    with pytest.raises(PolicyError, match=r"urgency: .* is outside 0-9"):
        select(Proximity(), urgency=urgency, distance=[1.0, 1.0], marker=[1, 2])


@pytest.mark.parametrize("distance", [[-0.5, 1.0], [1.0, math.nan], [-math.inf, 1.0]])
def test_negative_or_nan_distance_is_refused(distance):
    with pytest.raises(PolicyError, match=r"distance: .* must be >= 0 metres"):
        select(Proximity(), urgency=[1, 1], distance=distance, marker=[1, 2])


def test_invalid_values_are_refused_even_where_unavailable():
    with pytest.raises(PolicyError, match="distance"):
        select(
            Proximity(), urgency=[1, 1], distance=[math.nan, 1.0], marker=[1, 2],
            available=[False, True],
        )  # fmt: skip


def test_marker_must_be_integers():
    with pytest.raises(PolicyError, match="marker: must hold integers"):
        select(Proximity(), urgency=[1, 1], distance=[1.0, 1.0], marker=[1.0, 2.0])


def test_available_must_be_booleans():
    with pytest.raises(PolicyError, match="available: must hold booleans"):
        select(Proximity(), urgency=[1, 1], distance=[1.0, 1.0], marker=[1, 2], available=[1, 0])


@pytest.mark.parametrize(
    ("name", "scene"),
    [
        ("urgency", {"urgency": ["a", "b"], "distance": [1.0, 1.0], "marker": [1, 2]}),
        ("distance", {"urgency": [1, 1], "distance": [[1.0], [1.0, 2.0]], "marker": [1, 2]}),
    ],
)
def test_non_numeric_inputs_are_refused(name, scene):
    with pytest.raises(PolicyError, match=name):
        select(Proximity(), **scene)


def test_policy_must_be_a_policy():
    with pytest.raises(PolicyError, match="policy: 'proximity' is not a Policy"):
        select("proximity", urgency=[1], distance=[1.0], marker=[1])


def test_best_of_takes_the_largest_score_by_the_tie_rule_and_changes_no_input():
    from swarmtag.policy import best_of

    scores = np.array([[3.0, 5.0, 5.0, 9.0]])
    distance = np.array([[1.0, 2.0, 1.5, 0.5]])
    available = np.array([[True, True, True, False]])
    kept = scores.copy()
    chosen = best_of(scores, distance=distance, marker=np.arange(4), available=available)
    assert chosen.tolist() == [2]  # 9 is not available; of the two 5s, the nearer
    assert np.array_equal(scores, kept)
    assert (
        best_of(scores, distance=distance, marker=np.arange(4), available=~available | False)[0]
        == 3
    )
