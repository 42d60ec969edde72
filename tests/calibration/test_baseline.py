"""Event logs as baselines: the KPIs of ``swarmtag metrics`` become one set-up's targets."""

from __future__ import annotations

import numpy as np
import pytest

from swarmtag.analysis import CORE_METRICS, summarize
from swarmtag.calibration import load_baseline, targets_from_log
from swarmtag.calibration.spec import file_digest
from swarmtag.data import example_trial_path
from swarmtag.errors import CalibrationError
from swarmtag.io import CarrierLog, read_event_log, write_event_log


@pytest.fixture(scope="module")
def example():
    return load_baseline(str(example_trial_path()))


def test_the_example_trial_log_becomes_one_setup(example):
    log = read_event_log(example_trial_path())
    proximity = log.condition == "proximity"
    (setup,) = example.setups
    assert (example.kind, example.condition, example.time_unit) == ("event log", "proximity", "s")
    assert example.source_digest == file_digest(example_trial_path())
    assert setup.name == "example_trial"
    assert setup.runs == len(np.unique(log.run[proximity]))
    assert setup.scenario == {
        "robots": int(log.robot[proximity].max()) + 1,
        "carriers": int(np.sum(proximity)) // setup.runs,
    }
    report = summarize(log, n_resamples=10_000, seed=0).condition("proximity")
    assert [target.kpi for target in setup.kpis] == list(CORE_METRICS)
    for target in setup.kpis:
        estimate = report.estimate(target.kpi)
        assert target.value == estimate.value
        assert target.low == min(estimate.confidence_interval.low, estimate.value)
        assert target.high == max(estimate.confidence_interval.high, estimate.value)
        assert target.weight == 1.0


def test_another_condition_by_name():
    targets = load_baseline(str(example_trial_path()), condition="urgency:alpha=3.0")
    assert targets.condition == "urgency:alpha=3.0"
    with pytest.raises(CalibrationError, match=r"--condition 'urgency': .* has conditions"):
        load_baseline(str(example_trial_path()), condition="urgency")


def _log(conditions, carriers_per_run=(2, 2), robots=(0, 1)) -> CarrierLog:
    rows = {"condition": [], "run": [], "carrier": [], "robot": []}
    for condition in conditions:
        for run, count in enumerate(carriers_per_run):
            for carrier in range(count):
                rows["condition"].append(condition)
                rows["run"].append(run)
                rows["carrier"].append(carrier)
                rows["robot"].append(robots[carrier % len(robots)])
    n = len(rows["run"])
    return CarrierLog(
        condition=rows["condition"],
        run=rows["run"],
        seed=[0] * n,
        carrier=rows["carrier"],
        urgency0=[5] * n,
        order_time=[-10.0] * n,
        pickup_time=[float(5 + i) for i in range(n)],
        delivery_time=[float(10 + 3 * i) for i in range(n)],
        robot=rows["robot"],
        time_unit="s",
    )


def test_condition_choice_and_refusals():
    only = targets_from_log(_log(["weighted:w=0.5"]), source="x.csv", source_digest="d")
    assert only.condition == "weighted:w=0.5"
    with pytest.raises(CalibrationError, match="none is proximity: name the baseline with"):
        targets_from_log(_log(["a:x", "weighted:w=0.5"]), source="x.csv", source_digest="d")
    with pytest.raises(CalibrationError, match="have 2 to 3 carriers"):
        targets_from_log(_log(["proximity"], (2, 3)), source="x.csv", source_digest="d")
    with pytest.raises(CalibrationError, match=r"calibration\.condition: "):
        targets_from_log(_log(["nearest-first"]), source="x.csv", source_digest="d")


def test_a_kpi_the_log_leaves_undefined_is_left_out_with_a_note():
    log = _log(["proximity"], (1, 1), robots=(3,))  # one delivery per run: no throughput
    targets = targets_from_log(log, source="one.csv", source_digest="d")
    (setup,) = targets.setups
    assert "throughput" not in [target.kpi for target in setup.kpis]
    assert targets.notes == ("throughput is undefined in the baseline, so it is not a target",)
    assert setup.scenario == {"robots": 4, "carriers": 1}


def test_files_missing_or_in_an_unknown_format(tmp_path):
    with pytest.raises(CalibrationError, match="no such event log"):
        load_baseline(str(tmp_path / "none.csv"))
    write_event_log(_log(["proximity"]), tmp_path / "trials.csv")
    targets = load_baseline(str(tmp_path / "trials.csv"))
    assert targets.setups[0].name == "trials"
    with pytest.raises(CalibrationError, match="not a file, and no shipped baseline"):
        load_baseline(str(tmp_path / "trials.xlsx"))
