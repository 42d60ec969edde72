"""The shipped profiles were written by swarmtag calibrate from the shipped target files."""

from __future__ import annotations

import shlex

import pytest

from swarmtag.calibration import TARGETS, target_path
from swarmtag.calibration.spec import file_digest
from swarmtag.sim import load_profile
from swarmtag.sim.config.mapping import flat_keys


@pytest.mark.parametrize("name", ["paper-sim", "lab"])
def test_a_shipped_profile_records_its_calibration_on_the_shipped_targets(name):
    assert name in TARGETS
    profile = load_profile(name)
    record = profile.calibration
    assert record["baseline"] == name
    assert record["baseline_sha256"] == file_digest(target_path(name))  # targets unchanged
    assert record["condition"] == "proximity"  # the baselines only, never the treatments
    values = flat_keys(profile.values)
    for key, value in record["fitted"].items():
        assert values[key] == value
    for key, value in record["settings"].items():
        assert values[key] == value
    command = shlex.split(record["command"])
    assert command[:4] == ["swarmtag", "calibrate", "--baseline", name]
    assert f"src/swarmtag/sim/config/presets/{name}.toml" in command
