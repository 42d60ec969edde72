"""Pure batched geometry: contacts, steps, turns, walls, ordered sums."""

from __future__ import annotations

import math

import numpy as np
import pytest

from swarmtag.sim.model.geometry import (
    FACE_NORMALS,
    clamp_to_box,
    contact_depth,
    contact_push,
    contact_xy,
    length,
    length_xy,
    ordered_sum,
    step_towards,
    turn_towards,
)


def test_length_is_sqrt_of_squares_not_hypot():
    v = np.array([[3e-200, 4e-200], [3.0, 4.0]])
    # hypot would give 5e-200; the contract is sqrt(x*x + y*y), which underflows to 0
    assert length(v).tolist() == [0.0, 5.0]
    assert length_xy(v[:, 0], v[:, 1]).tolist() == [0.0, 5.0]


@pytest.mark.parametrize("inside", [False, True], ids=["all-outside", "some-inside"])
def test_contact_depth_is_contact_xy_s_depth_bit_for_bit(inside):
    rng = np.random.default_rng(11)
    dx, dy = rng.uniform(-0.6, 0.6, size=(2, 400))
    extent = rng.choice([0.0, 0.1775, 0.355], size=400)
    radius = np.where(extent == 0.355, 0.0, rng.choice([0.125, 0.25], size=400))
    dx[:3], dy[:3] = 0.0, 0.0  # coincident centres
    if not inside:
        keep = (np.abs(dx) > extent) | (np.abs(dy) > extent)
        dx, dy, extent, radius = dx[keep], dy[keep], extent[keep], radius[keep]
    _, _, expected = contact_xy(dx, dy, extent, radius, 1.0)
    depth = contact_depth(dx, dy, extent, radius)
    assert depth.tobytes() == expected.tobytes()
    assert (depth > 0).any()
    assert (depth <= 0).any()


@pytest.mark.parametrize(
    ("offset", "extent", "radius", "push", "depth"),
    [
        ((0.2, 0.0), 0.0, 0.25, (0.05, 0.0), 0.05),  # two discs
        ((0.3, 0.0), 0.0, 0.25, (0.0, 0.0), -0.05),  # apart
        ((0.0, 0.25), 0.1775, 0.125, (0.0, 0.0525), 0.0525),  # disc above a square's face
        ((0.2775, 0.2775), 0.1775, 0.125, (0.0, 0.0), None),  # disc off a corner, diagonal
        ((0.3, -0.1), 0.355, 0.0, (0.055, 0.0), 0.055),  # two squares, least overlap in x
        ((0.0, 0.0), 0.0, 0.25, (0.25, 0.0), 0.25),  # coincident: x axis, tie sign +1
    ],
)
def test_contact_push(offset, extent, radius, push, depth):
    got_push, got_depth = contact_push(np.array(offset), np.array(extent), np.array(radius), 1.0)
    assert got_push == pytest.approx(push, abs=1e-12)
    if depth is not None:
        assert float(got_depth) == pytest.approx(depth, abs=1e-12)


def test_disc_near_a_square_corner_is_pushed_along_the_diagonal():
    d = 0.1775 + 0.05
    push, depth = contact_push(np.array([d, d]), np.array(0.1775), np.array(0.125), 1.0)
    expected = 0.125 - math.sqrt(2) * 0.05
    assert float(depth) == pytest.approx(expected)
    assert push[0] == pytest.approx(push[1])
    assert float(length(push)) == pytest.approx(expected)


def test_pairs_outside_the_summed_box_get_the_same_bits_alone_as_beside_an_inside_one():
    # contact_xy takes a shorter path when every centre lies outside the summed box
    rng = np.random.default_rng(9)
    dx, dy = rng.uniform(-0.6, 0.6, (2, 300))
    extent = np.where(rng.random(300) < 0.5, 0.1775, 0.0)
    radius = np.full(300, 0.125)
    outside = (np.abs(dx) > extent) | (np.abs(dy) > extent)
    dx, dy, extent, radius = dx[outside], dy[outside], extent[outside], radius[outside]
    assert (contact_xy(dx, dy, extent, radius, 1.0)[2] > 0).any()  # some touch, some do not
    inside = [np.append(v, centre) for v, centre in ((dx, 0.01), (dy, 0.0), (extent, 0.1775))]
    alone = contact_xy(dx, dy, extent, radius, 1.0)
    beside = contact_xy(*inside, np.append(radius, 0.125), 1.0)
    for ours, theirs in zip(alone, beside, strict=True):
        assert ours.tobytes() == theirs[:-1].tobytes()


def test_contact_push_is_antisymmetric():
    rng = np.random.default_rng(4)
    offsets = rng.normal(scale=0.2, size=(200, 2))
    extent = np.full(200, 0.1775)
    radius = np.full(200, 0.125)
    forward, _ = contact_push(offsets, extent, radius, 1.0)
    backward, _ = contact_push(-offsets, extent, radius, -1.0)
    assert np.array_equal(forward, -backward)


def test_step_towards_lands_exactly_or_moves_one_step():
    pos = np.array([[0.0, 0.0], [1.0, 1.0], [2.0, 2.0]])
    goal = np.array([[0.03, 0.04], [1.0, 2.0], [2.0, 2.0]])
    moved = step_towards(pos, goal, np.array([0.05, 0.05, 0.05]))
    assert moved[0].tolist() == [0.03, 0.04]  # nearer than a step: exactly on the goal
    assert moved[1].tolist() == [1.0, 1.05]
    assert moved[2].tolist() == [2.0, 2.0]


def test_turn_towards_is_limited_and_snaps():
    cos_step, sin_step = math.cos(math.radians(9)), math.sin(math.radians(9))
    heading = np.array([1.0, 0.0])
    target = np.array([0.0, 1.0])
    turns = 0
    while not np.array_equal(heading, target):
        heading = turn_towards(heading, target, cos_step, sin_step)
        assert float(length(heading)) == pytest.approx(1.0, abs=1e-15)
        turns += 1
    assert turns == 10  # 90 degrees at 9 degrees per tick
    clockwise = turn_towards(np.array([1.0, 0.0]), np.array([0.0, -1.0]), cos_step, sin_step)
    assert clockwise[1] < 0


def test_clamp_keeps_bodies_inside():
    pos = np.array([[-1.0, 5.0], [1.0, 1.0]])
    clamped = clamp_to_box(pos, np.array([0.125, 0.1775]), 3.75)
    assert clamped.tolist() == [[0.125, 3.625], [1.0, 1.0]]


def test_ordered_sum_is_left_to_right():
    values = np.array([[1.0, 1e16, -1e16], [1e16, 1.0, -1e16]])
    # left to right: (1 + 1e16) - 1e16 = 0 and (1e16 + 1) - 1e16 = 0; pairwise could differ
    assert ordered_sum(values, axis=1).tolist() == [0.0, 0.0]
    assert ordered_sum(np.zeros((2, 0)), axis=1).tolist() == [0.0, 0.0]


def test_face_normals_are_east_north_west_south():
    assert FACE_NORMALS.tolist() == [[1.0, 0.0], [0.0, 1.0], [-1.0, 0.0], [0.0, -1.0]]


def test_bearing_factor_matches_its_compiled_twin_bit_for_bit():
    import numba

    from swarmtag.sim.config.bearing import bearing_profile
    from swarmtag.sim.fast._geometry import bearing_factor as compiled
    from swarmtag.sim.model.geometry import bearing_factor

    @numba.njit
    def scalar(ox, oy, d, hx, hy, cosines, factors):  # noqa: PLR0917 - the twin's arguments
        return compiled(ox, oy, d, hx, hy, cosines, factors)

    cosines, factors = bearing_profile("dots")
    rng = np.random.default_rng(4)
    offset = rng.normal(size=(500, 2))
    offset[:3] = [[0.0, 0.0], [1.0, 0.0], [-2.0, 0.0]]  # the robot's centre, ahead, behind
    heading = rng.normal(size=(500, 2))
    heading /= length(heading)[:, None]
    heading[:3] = [1.0, 0.0]
    distance = length(offset)
    batched = bearing_factor(
        offset[:, 0], offset[:, 1], distance, heading, cosines=cosines, factors=factors
    )
    one_by_one = [
        scalar(o[0], o[1], d, h[0], h[1], cosines, factors)
        for o, d, h in zip(offset, distance, heading, strict=True)
    ]
    assert batched.tolist() == one_by_one
    assert batched[:3].tolist() == [1.0, 1.0, factors[-1]]
    assert batched.min() >= factors.min()
    assert batched.max() <= factors.max()
