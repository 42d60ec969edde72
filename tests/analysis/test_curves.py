"""PA and latency curves with bootstrap bands."""

from __future__ import annotations

import numpy as np
import pytest

from swarmtag.analysis import (
    CURVE_THRESHOLDS,
    LATENCY_PERCENTILES,
    ConditionRuns,
    condition_statistics,
    priority_alignment,
)
from swarmtag.analysis.curves import interval_percentiles
from tests.analysis.test_kpis import WORKED
from tests.io.strategies import log_from_rows


@pytest.mark.parametrize(
    ("level", "bounds"), [(0.95, (2.5, 97.5)), (0.9, (5.0, 95.0)), (0.99, (0.5, 99.5))]
)
def test_interval_percentiles_are_exact(level, bounds):
    assert interval_percentiles(level) == bounds


def test_curves_of_the_worked_example():
    runs = ConditionRuns.from_log(log_from_rows(WORKED), "proximity")
    statistics = condition_statistics(runs, n_resamples=500, seed=2)
    pa_curve = statistics.pa_curve
    assert pa_curve.x.tolist() == list(CURVE_THRESHOLDS)
    expected = priority_alignment(runs, CURVE_THRESHOLDS).mean(axis=0)
    np.testing.assert_array_equal(pa_curve.value, expected)
    # PA(100) of the three runs: 4/5, 1/3 and 1 (delivered / carriers) -> mean 32/45.
    assert pa_curve.value[-1] == pytest.approx(32 / 45)
    latency_curve = statistics.latency_curve
    assert latency_curve.x.tolist() == list(LATENCY_PERCENTILES)
    # Pooled latencies 14, 16, 16, 22, 22, 28, 36: the 0th percentile is 14, the 100th 36.
    assert (latency_curve.value[0], latency_curve.value[-1]) == (14.0, 36.0)
    assert latency_curve.value[LATENCY_PERCENTILES.index(95)] == statistics.p95_latency.value
    for curve in (pa_curve, latency_curve):
        assert (curve.low <= curve.value + 1e-12).all()
        assert (curve.value <= curve.high + 1e-12).all()


def test_curve_bands_are_the_percentiles_of_the_resampled_curves():
    rows = [
        ("c", run, carrier, (run * 3 + carrier) % 10, -float(carrier), 5.0 + run + 2 * carrier)
        for run in range(8)
        for carrier in range(6)
    ]
    runs = ConditionRuns.from_log(log_from_rows(rows), "c")
    narrow = condition_statistics(
        runs, n_resamples=300, curve_thresholds=[50], curve_percentiles=[95]
    )
    # The 95th-percentile point of the latency curve is the P95 KPI, with the same band.
    assert narrow.latency_curve.low[0] == narrow.p95_latency.confidence_interval.low
    assert narrow.latency_curve.high[0] == narrow.p95_latency.confidence_interval.high
