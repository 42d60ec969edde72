"""Urgency models of SPEC §4.3 against hand-computed values, in the kernel and in the logs."""

from __future__ import annotations

import numpy as np
import pytest

from swarmtag.policy import Proximity
from swarmtag.sim import Scenario, UrgencyModel, simulate
from swarmtag.sim.world.urgency import growing_urgency, initial_urgency, static_urgency


@pytest.mark.parametrize(
    ("w0", "t", "expected"),
    [
        (0.0, 0, 0),
        (333.0, 0, 0),  # 9 * 333 / 3000 = 0.999
        (334.0, 0, 1),  # 1.002
        (1500.0, 0, 4),
        (1500.0, 1000, 7),  # 9 * 2500 / 3000 = 7.5
        (2999.0, 1, 9),
        (3000.0, 0, 9),
        (3000.0, 3000, 9),  # saturates
        (1000.0, 1000, 6),  # exactly 6.0
    ],
)
def test_growing_model(w0, t, expected):
    assert growing_urgency(np.array([w0]), t, 3000.0).tolist() == [expected]


@pytest.mark.parametrize(
    ("tau", "expected"),
    [(0.0, 9), (23.99, 9), (24.0, 9), (24.01, 8), (120.0, 5), (215.0, 1), (217.0, 0), (239.9, 0)],
)
def test_static_model(tau, expected):
    # the formula: u is min(9, floor(10 times (1 - tau / 240)))
    assert static_urgency(np.array([tau]), 240.0).tolist() == [expected]


def test_order_times():
    grow = initial_urgency(np.array([0.25, 0.0]), growing=True, horizon=3000.0, horizon_s=240.0)
    assert grow.order_time.tolist() == [-750.0, 0.0]
    assert grow.urgency0.tolist() == [2, 0]
    static = initial_urgency(np.array([0.0, 0.5]), growing=False, horizon=2400.0, horizon_s=240.0)
    assert static.urgency0.tolist() == [9, 5]
    # -(u / 9) * 240 s, in ticks of 0.1 s
    assert static.order_time.tolist() == [-2400.0, -(5 / 9) * 2400.0]
    assert np.isnan(static.w0).all()


def test_simulated_logs_follow_the_formulas():
    growing = simulate(Scenario(ticks=3000), Proximity(), seed=11, runs=3).carriers
    w0 = -growing.order_time
    assert (w0 >= 0).all()
    assert (w0 <= 3000).all()
    assert growing.urgency0.tolist() == np.minimum(9, np.floor(9 * w0 / 3000)).astype(int).tolist()

    static = simulate(
        Scenario(urgency=UrgencyModel(model="static", static_time_limit=600)),
        Proximity(),
        seed=11,
        runs=3,
    ).carriers
    assert static.order_time.tolist() == (-(static.urgency0 / 9) * 2400.0 + 0.0).tolist()


def test_kernel_grows_urgency_each_tick():
    from swarmtag.sim import Scene
    from tests.sim.helpers import params_for, run_script

    params = params_for(robots=1, carriers=2, ticks=100)
    scene = Scene.build(
        robots=[(3.4, 3.4)],
        carriers=[(0.3, 0.3), (0.3, 1.3)],
        urgency=[2, 7],
        w0=[25.0, np.nan],
    )
    for ticks in (0, 5, 19, 50, 100):
        state = run_script(params, scene, ticks, walk=(0.0, -1.0)).final_state
        expected = min(9, int(np.floor(9 * (25.0 + ticks) / 100)))
        assert state.urgency[0].tolist() == [expected, 7]
