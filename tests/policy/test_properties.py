"""Hypothesis properties of select and choose on random (runs, robots, carriers) scenes."""

from __future__ import annotations

import math

import numpy as np
from hypothesis import given
from hypothesis import strategies as st
from hypothesis.extra import numpy as hnp

from swarmtag.policy import (
    Candidate,
    Edf,
    Proximity,
    Urgency,
    Weighted,
    choose,
    parse_policy,
    select,
)

# A few round distances make exact score ties (and equal distances) common.
DISTANCES = st.one_of(
    st.sampled_from([0.0, 0.9, 1.8, 2.7, 3.6, 4.0, 7.5, math.inf]),
    st.floats(min_value=0.0, max_value=8.0),
)
POLICIES = st.one_of(
    st.just(Proximity()),
    st.just(Edf()),
    st.sampled_from([0.3, 0.5, 0.7, 0.9, 2.25, 3.0, 9.0]).map(Urgency),
    st.floats(min_value=1e-3, max_value=1e3).map(Urgency),
    st.sampled_from([0.0, 0.3, 0.5, 1.0]).map(Weighted),
    st.floats(min_value=0.0, max_value=1.0).map(Weighted),
)


@st.composite
def scenes(draw, max_carriers=6):
    """(runs, robots, carriers) arrays; markers unique within each robot's row."""
    shape = (draw(st.integers(1, 3)), draw(st.integers(1, 3)), draw(st.integers(0, max_carriers)))
    urgency = draw(hnp.arrays(np.int64, shape, elements=st.integers(0, 9)))
    distance = draw(hnp.arrays(np.float64, shape, elements=DISTANCES))
    available = draw(hnp.arrays(np.bool_, shape))
    rows = [
        draw(st.lists(st.integers(0, 255), min_size=shape[2], max_size=shape[2], unique=True))
        for _ in range(shape[0] * shape[1])
    ]
    marker = np.array(rows, dtype=np.int64).reshape(shape)
    return {"urgency": urgency, "distance": distance, "marker": marker, "available": available}


def rows_of(scene):
    runs, robots, _ = scene["urgency"].shape
    for r in range(runs):
        for b in range(robots):
            yield (r, b), {key: value[r, b] for key, value in scene.items()}


def reference_choice(policy, row):
    """Independent oracle: the available carrier with the smallest (-score, distance, marker)."""
    keys = [
        (-float(policy.score(int(u), float(d))), float(d), int(m), i)
        for i, (u, d, m, a) in enumerate(
            zip(row["urgency"], row["distance"], row["marker"], row["available"], strict=True)
        )
        if a
    ]
    return min(keys)[3] if keys else -1


@given(POLICIES, scenes())
def test_batched_select_equals_per_robot_select_and_the_oracle(policy, scene):
    batched = select(policy, **scene)
    assert batched.shape == scene["urgency"].shape[:2]
    assert batched.dtype == np.intp
    for at, row in rows_of(scene):
        single = select(policy, **row)
        assert single.shape == ()
        assert batched[at] == single
        assert batched[at] == reference_choice(policy, row)


@given(POLICIES, scenes())
def test_batched_select_equals_choose_on_candidate_lists(policy, scene):
    batched = select(policy, **scene)
    for at, row in rows_of(scene):
        candidates = [
            Candidate(marker=int(m), urgency=int(u), distance=float(d))
            for u, d, m, a in zip(
                row["urgency"], row["distance"], row["marker"], row["available"], strict=True
            )
            if a
        ]
        chosen = choose(policy, candidates)
        if batched[at] < 0:
            assert chosen is None
        else:
            assert chosen is not None
            assert chosen.marker == row["marker"][batched[at]]


@given(POLICIES, scenes())
def test_chosen_carrier_is_available_and_scores_highest(policy, scene):
    index = select(policy, **scene)
    scores = policy.score(scene["urgency"], scene["distance"])
    for at, row in rows_of(scene):
        i = index[at]
        if i < 0:
            assert not row["available"].any()
            continue
        assert row["available"][i]
        assert (scores[at][i] >= scores[at][row["available"]]).all()


@given(POLICIES, scenes(), st.randoms(use_true_random=False))
def test_permuting_carriers_chooses_the_same_marker(policy, scene, random):
    carriers = scene["urgency"].shape[-1]
    order = list(range(carriers))
    random.shuffle(order)
    permuted = {key: value[..., order] for key, value in scene.items()}
    before = select(policy, **scene)
    after = select(policy, **permuted)
    for at, row in rows_of(scene):
        if before[at] < 0:
            assert after[at] == -1
        else:
            assert permuted["marker"][at][after[at]] == row["marker"][before[at]]


@given(POLICIES, scenes(max_carriers=4))
def test_broadcast_inputs_equal_materialised_inputs(policy, scene):
    # one marker row for every robot, as the simulator passes it
    shared = {**scene, "marker": np.arange(scene["urgency"].shape[-1])}
    full = {**shared, "marker": np.broadcast_to(shared["marker"], scene["urgency"].shape).copy()}
    np.testing.assert_array_equal(select(policy, **shared), select(policy, **full))


@given(POLICIES, scenes())
def test_default_mask_means_all_available(policy, scene):
    everything = {**scene, "available": np.ones_like(scene["available"])}
    without = {key: value for key, value in scene.items() if key != "available"}
    np.testing.assert_array_equal(select(policy, **without), select(policy, **everything))


@given(POLICIES, st.integers(0, 9), st.floats(min_value=0.0, max_value=10.0))
def test_scalar_score_is_bit_identical_to_array_score(policy, urgency, distance):
    array = policy.score(np.array([urgency, urgency]), np.array([distance, 0.0]))
    assert array[0] == policy.score(urgency, distance)


@given(POLICIES)
def test_policy_name_round_trips(policy):
    assert parse_policy(policy.name) == policy
