"""``write_profile_file``: the TOML layout of profiles, written atomically, read back exactly."""

from __future__ import annotations

import dataclasses
import tomllib

import pytest

from swarmtag.errors import ConfigError
from swarmtag.sim.config.profiles import (
    PROFILES,
    load_profile,
    profile_path,
    read_profile_file,
    write_profile_file,
)


@pytest.mark.parametrize("name", [name for name in PROFILES if profile_path(name).is_file()])
def test_a_shipped_profile_round_trips(tmp_path, name):
    profile = load_profile(name)
    back = read_profile_file(write_profile_file(tmp_path / "p.toml", profile))
    assert (back.name, back.description, back.values, back.calibration) == (
        profile.name,
        profile.description,
        profile.values,
        profile.calibration,
    )


def test_calibration_records_nested_tables_and_events_round_trip(tmp_path):
    base = load_profile("base")
    profile = dataclasses.replace(
        base,
        name="fitted",
        values={**base.values, "reprioritisations": [{"tick": 5, "carrier": 1, "urgency": 9}]},
        calibration={
            "objective": 0.1 + 0.2,
            "free": ["timing.dock=0.5:8.0:log"],
            "fitted": {"timing.dock": 2.713},
            "runs": {"3x7": 100, "5x10": 21},
            "command": 'swarmtag calibrate --set "urgency.model=static"',
        },
    )
    path = write_profile_file(tmp_path / "p.toml", profile)
    back = read_profile_file(path)
    assert back.values == profile.values
    assert back.calibration == profile.calibration
    assert back.calibration["objective"] == 0.1 + 0.2  # floats exactly
    text = path.read_text(encoding="utf-8")
    # The layout: scalar scenario keys, then [profile], then the scenario tables.
    assert text.index("tick = ") < text.index("[profile]") < text.index("[motion]")
    assert text.index("[profile.calibration]") < text.index("[motion]")
    assert tomllib.loads(text)["profile"]["name"] == "fitted"
    assert list(tmp_path.iterdir()) == [path]  # no temporary file left behind


def test_refusals(tmp_path):
    with pytest.raises(FileNotFoundError):
        write_profile_file(tmp_path / "missing" / "p.toml", load_profile("base"))
    broken = dataclasses.replace(load_profile("base"), calibration={"objective": None})
    with pytest.raises(ConfigError, match="cannot be written as TOML"):
        write_profile_file(tmp_path / "p.toml", broken)
    assert not (tmp_path / "p.toml").exists()
