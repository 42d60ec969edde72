"""Initial scenes: inside their areas, without overlap, reproducible, policy-independent."""

from __future__ import annotations

import numpy as np
import pytest

from swarmtag.errors import ConfigError
from swarmtag.policy import Proximity, Urgency
from swarmtag.sim import Arena, Realism, Scenario, Scene, make_params, sample_scene
from swarmtag.sim.model.geometry import length
from swarmtag.sim.model.scene import PLACE_ATTEMPTS, grid_place
from swarmtag.sim.model.scene import _place as place


@pytest.mark.parametrize(("robots", "carriers"), [(3, 7), (10, 20), (20, 40)])
def test_scenes_respect_areas_and_spacing(robots, carriers):
    params = make_params(Scenario(robots=robots, carriers=carriers), Proximity())
    for run in range(10):
        scene = sample_scene(params, seed=0, run=run)
        half, r = params.carrier_half, params.robot_radius
        c = scene.carrier_pos
        assert (c[:, 0] >= half).all()
        assert (c[:, 0] <= params.pickup_right - half).all()
        assert (c[:, 1] >= half).all()
        assert (c[:, 1] <= params.arena - half).all()
        gaps = np.abs(c[:, None] - c[None, :]).max(axis=-1) + np.eye(carriers) * 99
        assert gaps.min() >= 2 * half + params.carrier_spacing
        p = scene.robot_pos
        assert (p[:, 0] >= params.dropoff_left + r).all()
        assert (p[:, 0] <= params.arena - r).all()
        apart = length(p[:, None] - p[None, :]) + np.eye(robots) * 99
        assert apart.min() >= 2 * r
        assert np.allclose(length(scene.heading), 1.0)
        assert (scene.speed_factor == 1.0).all()


def test_same_seed_and_run_same_scene_under_any_policy():
    a = sample_scene(make_params(Scenario(), Proximity()), seed=4, run=2)
    b = sample_scene(make_params(Scenario(), Urgency(alpha=9.0)), seed=4, run=2)
    c = sample_scene(make_params(Scenario(), Proximity()), seed=4, run=3)
    assert np.array_equal(a.carrier_pos, b.carrier_pos)
    assert np.array_equal(a.robot_pos, b.robot_pos)
    assert np.array_equal(a.urgency0, b.urgency0)
    assert not np.array_equal(a.carrier_pos, c.carrier_pos)


def test_speed_variation_changes_only_the_speed_factors():
    plain = sample_scene(make_params(Scenario(), Proximity()), seed=1, run=0)
    varied = sample_scene(
        make_params(Scenario(realism=Realism(speed_variation=0.3)), Proximity()), seed=1, run=0
    )
    assert np.array_equal(plain.carrier_pos, varied.carrier_pos)
    assert np.array_equal(plain.heading, varied.heading)
    assert not np.array_equal(plain.speed_factor, varied.speed_factor)
    assert ((varied.speed_factor >= 0.5) & (varied.speed_factor <= 1.5)).all()


def test_a_pick_up_area_too_crowded_for_random_placement_gets_the_densest_grid():
    # 3 carriers fit in a column only with (almost) no slack: random placement cannot
    # find it, so they stand on the grid's three cells, in an order drawn from the stream
    crowded = Scenario(carriers=3, arena=Arena(pickup_width=1.0, carrier_spacing=1.3424))
    scene = sample_scene(make_params(crowded, Proximity()), seed=0, run=0)
    half, pitch = 0.1775, 0.355 + 1.3424
    assert sorted(scene.carrier_pos.tolist()) == [[half, half + k * pitch] for k in range(3)]
    again = sample_scene(make_params(crowded, Proximity()), seed=0, run=0)
    assert np.array_equal(scene.carrier_pos, again.carrier_pos)
    other = [sample_scene(make_params(crowded, Proximity()), seed=s, run=0) for s in range(1, 6)]
    assert any(not np.array_equal(o.carrier_pos, scene.carrier_pos) for o in other)


def _one_at_a_time(rng, count, low, high, pitch):
    """SPEC 4.1's placement as written: one candidate pair a draw, Chebyshev apart, 100 restarts."""
    for _ in range(100):
        placed = []
        for _ in range(count):
            for _ in range(PLACE_ATTEMPTS):
                ux, uy = rng.random(2).tolist()
                x, y = low[0] + ux * (high[0] - low[0]), low[1] + uy * (high[1] - low[1])
                if all(max(abs(x - ox), abs(y - oy)) >= pitch for ox, oy in placed):
                    placed.append((x, y))
                    break
            else:
                break
        else:
            return np.array(placed)
    return grid_place(rng, count, low=np.array(low), high=np.array(high), pitch=pitch)


@pytest.mark.parametrize(("count", "side"), [(7, 6.0), (12, 4.2), (16, 3.0)])
def test_candidates_tested_in_blocks_give_one_at_a_time_s_points_and_stream(count, side):
    # a crowded square (most candidates rejected, the kept one mid-block), one crowded to
    # the grid fallback (16 of pitch 1 in 3 x 3 m, its 16 cells: placing gives up 100 times)
    def apart(xs, ys, others):
        gap = np.maximum(np.abs(xs[:, None] - others[:, 0]), np.abs(ys[:, None] - others[:, 1]))
        return (gap >= 1.0).all(axis=1)

    for seed in range(3):
        blocked, plain = np.random.default_rng(seed), np.random.default_rng(seed)
        low, high = np.zeros(2), np.full(2, side)
        points = place(blocked, count, low=low, high=high, far_enough=apart, pitch=1.0)
        expected = _one_at_a_time(plain, count, (0.0, 0.0), (side, side), 1.0)
        assert points.tobytes() == expected.tobytes()
        assert blocked.random() == plain.random()  # the stream left at the same place


def test_the_grid_refuses_more_bodies_than_cells():
    with pytest.raises(ConfigError, match="5 bodies do not fit on a 2 x 2 grid"):
        grid_place(np.random.default_rng(0), 5, low=np.zeros(2), high=np.ones(2), pitch=1.0)


def test_hand_built_scene_defaults():
    scene = Scene.build(robots=[(1.0, 1.0), (2.0, 2.0)], carriers=[(0.5, 0.5)])
    assert scene.heading.tolist() == [[1.0, 0.0], [1.0, 0.0]]
    assert scene.urgency0.tolist() == [0]
    assert np.isnan(scene.w0).all()
    assert scene.status.tolist() == [1]
    with pytest.raises(ConfigError, match=r"urgency: shape \(2,\) is not \(1,\)"):
        Scene.build(robots=[(1.0, 1.0)], carriers=[(0.5, 0.5)], urgency=[1, 2])
