"""The problem refuses, before any simulation, what would make a calibration wrong or endless."""

from __future__ import annotations

import re

import pytest

from swarmtag.calibration import CalibrationProblem, parse_free
from swarmtag.errors import CalibrationError
from swarmtag.sim.config.profiles import load_profile
from tests.calibration.helpers import tiny_problem, tiny_setup, tiny_targets


def test_layers_profile_then_set_then_free_then_setup():
    problem = tiny_problem(
        "timing.dock=0.5:8:log",
        settings={"timing.lift": 2.5, "camera": {"memory": 4.0}},
        targets=tiny_targets(tiny_setup(robots=2)),
    )
    scenario = problem.scenario(problem.targets.setups[0], {"timing.dock": 3.0})
    assert (scenario.timing.dock, scenario.timing.lift, scenario.camera.memory) == (3.0, 2.5, 4.0)
    assert (scenario.robots, scenario.ticks) == (2, 150)
    assert scenario.tick == load_profile("base").values["tick"]
    values = problem.profile_values({"timing.dock": 3.0})
    assert values["timing"]["dock"] == 3.0
    assert values["timing"]["lift"] == 2.5
    assert "robots" not in values  # the set-up's scenario is the experiment, not the profile


@pytest.mark.parametrize(
    ("free", "message"),
    [
        ("timing.dok=1:2", "--free timing.dok: not a scenario key"),
        ("colour=1:2", "--free colour: not a scenario key"),
        ("timing=1:2", "--free timing: not a scenario key"),
        ("motion.collision_iterations=2:9", "the setting is an integer (8)"),
        ("ticks=100:900", "set-up 'tiny' of tiny.toml sets it"),
        ("perception=1:2", "the setting is not a number ('disc')"),
        ("motion.avoid_taken_faces=0:1", "the setting is not a number (False)"),
        (
            "tick=-0.1:0.2",
            "LO = -0.1 is refused in set-up 'tiny' (tick: -0.1 is not a number in [1e-06, 3600])",
        ),
        ("realism.breakdown=0:2", "HI = 2 is refused in set-up 'tiny'"),
    ],
)
def test_free_parameters_are_checked_at_both_bounds(free, message):
    with pytest.raises(CalibrationError) as error:
        tiny_problem(free)
    assert message in str(error.value)
    assert "\n" not in str(error.value)


def test_conflicts_between_set_free_and_setups():
    with pytest.raises(
        CalibrationError, match=re.escape("--free timing.dock: --set timing.dock=... fixes")
    ):
        tiny_problem("timing.dock=0.5:8", settings={"timing": {"dock": 2.0}})
    with pytest.raises(CalibrationError, match=r"--set ticks: set-up 'tiny' .* sets it"):
        tiny_problem(settings={"ticks": 900})
    with pytest.raises(CalibrationError, match=re.escape("--free timing.lift: set-up 'tiny'")):
        tiny_problem("timing.lift=0.5:2", targets=tiny_targets(tiny_setup(**{"timing.lift": 1.0})))


def test_bad_settings_and_setups_are_named():
    with pytest.raises(CalibrationError, match=re.escape("--set: timing.dokk: unknown key")):
        tiny_problem(settings={"timing.dokk": 2.0})
    with pytest.raises(CalibrationError, match="set-up 'tiny' on profile 'base': robots: 0"):
        tiny_problem(targets=tiny_targets(tiny_setup(robots=0)))


def test_time_units_must_agree():
    seconds = tiny_targets(time_unit="s")
    with pytest.raises(CalibrationError) as error:
        tiny_problem(targets=seconds)
    assert str(error.value) == (
        "tiny.toml is in seconds but profile 'base' logs in ticks: use a profile with "
        'time_unit = "s" or --set time_unit=s'
    )
    assert tiny_problem(targets=seconds, settings={"time_unit": "s"}).targets.time_unit == "s"


@pytest.mark.parametrize(
    ("changes", "message"),
    [
        ({"runs": 0}, "--runs: 0 is not an integer in 1-10000"),
        ({"runs": 10_001}, "--runs: 10001 is not an integer in 1-10000"),
        ({"seed": -1}, "--seed: -1 is not an integer in 0-9223372036854775807"),
        ({"free": ()}, "no free parameters"),
    ],
)
def test_work_is_bounded(changes, message):
    with pytest.raises(CalibrationError, match=message):
        tiny_problem(**changes)


def test_cache_keys_cover_everything_that_changes_a_result():
    problem = tiny_problem()
    point = {"timing.dock": 2.0}
    key = problem.point_key(point)
    assert key == tiny_problem().point_key({"timing.dock": 2.0})
    others = [
        problem.point_key({"timing.dock": 2.0000000001}),
        tiny_problem(model="another-model").point_key(point),
        tiny_problem(seed=1).point_key(point),
        tiny_problem(runs=3).point_key(point),
        tiny_problem(settings={"timing.lift": 2.0}).point_key(point),
        tiny_problem(targets=tiny_targets(condition="urgency:alpha=0.7")).point_key(point),
        tiny_problem(targets=tiny_targets(tiny_setup(runs=3))).point_key(point),
        CalibrationProblem(
            targets=tiny_targets(),
            profile=load_profile("base"),
            free=(parse_free("timing.dock=0.1:9"),),
            model="test-model",
        ).point_key({"timing.dock": 2.5}),
    ]
    assert key not in others
    assert len(set(others)) == len(others)
    # The bounds are not part of the key: a point is the same point under other bounds.
    wider = CalibrationProblem(
        targets=tiny_targets(),
        profile=load_profile("base"),
        free=(parse_free("timing.dock=0.1:9"),),
        model="test-model",
    )
    assert wider.point_key(point) == key
