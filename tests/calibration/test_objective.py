"""The objective on hand-made numbers: residuals in CI half-widths, floors, penalties, weights."""

from __future__ import annotations

import math

import pytest

from swarmtag.calibration import (
    UNDEFINED_PENALTY,
    KpiFit,
    KpiTarget,
    Setup,
    fit_rows,
    half_width,
    objective,
    residual,
)
from swarmtag.calibration.objective import achieved_kpis
from swarmtag.io import CarrierLog
from tests.calibration.helpers import tiny_targets

P95 = KpiTarget("p95_latency", value=4979.0, low=4640.0, high=5086.0)


@pytest.mark.parametrize(
    ("achieved", "expected"),
    [
        (4979.0, 0.0),
        (5086.0, 1.0),  # the upper bound: one half-width, on the upper side
        (5193.0, 2.0),
        (4640.0, -1.0),  # the lower bound: the lower half-width (339)
        (4979.0 - 3 * 339.0, -3.0),
        (5000.0, 21.0 / 107.0),
    ],
)
def test_residual_uses_the_half_width_on_the_side_of_the_achieved_value(achieved, expected):
    assert math.isclose(residual(P95, achieved), expected, rel_tol=1e-12, abs_tol=1e-15)


def test_inside_the_ci_is_at_most_one_half_width():
    for achieved in (4640.0, 4700.0, 4979.0, 5086.0):
        assert abs(residual(P95, achieved)) <= 1.0
        assert KpiFit("s", P95, achieved, residual(P95, achieved)).inside
    for achieved in (4639.0, 5087.0):
        assert abs(residual(P95, achieved)) > 1.0
        assert not KpiFit("s", P95, achieved, residual(P95, achieved)).inside


def test_exact_targets_use_the_floors():
    exact = KpiTarget("total_deliveries", value=840.0, low=840.0, high=840.0)
    assert half_width(exact, 831.6) == pytest.approx(8.4)  # 1 % of 840
    assert residual(exact, 831.6) == pytest.approx(-1.0)
    assert not KpiFit("s", exact, 831.6, -1.0).inside
    zero = KpiTarget("undelivered", value=0.0, low=0.0, high=0.0)
    assert half_width(zero, 1.0) == 1e-6
    # A CI that is narrower than the floor on one side only: that side uses the floor.
    lopsided = KpiTarget("pa", value=0.5, low=0.499, high=0.6)
    assert half_width(lopsided, 0.4) == pytest.approx(0.005)
    assert half_width(lopsided, 0.55) == pytest.approx(0.1)


def test_undefined_achieved_values():
    assert residual(P95, None) is None
    assert residual(P95, float("nan")) is None
    fit = KpiFit("s", P95, None, None)
    assert fit.contribution == UNDEFINED_PENALTY
    assert not fit.inside
    heavy = KpiTarget("p95_latency", value=1.0, low=0.0, high=2.0, weight=2.5)
    assert KpiFit("s", heavy, None, None).contribution == 2.5 * UNDEFINED_PENALTY


def test_objective_is_the_weighted_sum_of_squares_and_weight_zero_only_reports():
    a = KpiTarget("p95_latency", value=10.0, low=8.0, high=14.0, weight=1.0)
    b = KpiTarget("pa", value=0.5, low=0.25, high=0.75, weight=3.0)
    c = KpiTarget("mean_latency", value=5.0, low=4.0, high=6.0, weight=0.0)
    rows = (
        KpiFit("s", a, 22.0, residual(a, 22.0)),  # r = 12 / 4 = 3 -> 9
        KpiFit("s", b, 0.0, residual(b, 0.0)),  # r = -2 -> 3 * 4 = 12
        KpiFit("s", c, 100.0, residual(c, 100.0)),  # weight 0: nothing
        KpiFit("s", c, None, None),  # weight 0 and undefined: nothing either
    )
    assert [row.contribution for row in rows] == [9.0, 12.0, 0.0, 0.0]
    assert objective(rows) == 21.0
    assert rows[2].residual == 95.0  # still reported


def test_fit_rows_follow_the_file_order_and_look_up_by_name():
    setup = Setup(
        name="x",
        runs=4,
        scenario={},
        kpis=(
            KpiTarget("pa", value=0.3, low=0.2, high=0.4),
            KpiTarget("p95_latency", value=100.0, low=90.0, high=120.0),
        ),
    )
    targets = tiny_targets(setup)
    rows = fit_rows(targets, {"x": {"p95_latency": 120.0, "pa": None}})
    assert [(row.setup, row.target.kpi, row.achieved) for row in rows] == [
        ("x", "pa", None),
        ("x", "p95_latency", 120.0),
    ]
    assert objective(rows) == UNDEFINED_PENALTY + 1.0


def _log() -> CarrierLog:
    """Two runs of two carriers: 3 deliveries (latencies 10, 20, 30), one never delivered."""
    nan = float("nan")
    return CarrierLog(
        condition=["proximity"] * 4,
        run=[0, 0, 1, 1],
        seed=[0] * 4,
        carrier=[0, 1, 0, 1],
        urgency0=[5, 3, 2, 1],
        order_time=[0.0, -10.0, 0.0, 0.0],
        pickup_time=[5.0, 6.0, 20.0, nan],
        delivery_time=[10.0, 10.0, 30.0, nan],
        robot=[0, 1, 0, -1],
    )


def test_achieved_kpis_by_name_and_counts_scaled_to_the_setups_runs():
    setup = Setup(
        name="x",
        runs=10,
        scenario={},
        kpis=(
            *(
                KpiTarget(kpi, value=1.0, low=0.0, high=100.0)
                for kpi in ("mean_latency", "throughput", "deliveries_per_run", "total_deliveries")
            ),
            KpiTarget("undelivered", value=0.0, low=0.0, high=5.0),
        ),
    )
    values = achieved_kpis(_log(), condition="proximity", setup=setup, simulated_runs=2)
    assert values == {
        "mean_latency": 20.0,
        "throughput": None,  # no run has two deliveries at different times
        "deliveries_per_run": 1.5,
        "total_deliveries": 15.0,  # 3 in 2 simulated runs, stated for 10
        "undelivered": 5.0,
    }
