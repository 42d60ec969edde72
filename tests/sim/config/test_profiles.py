"""Profiles (SPEC §4.6): shipped presets, layering, refusals."""

from __future__ import annotations

from importlib import resources
from pathlib import Path

import pytest

from swarmtag.errors import ConfigError
from swarmtag.sim import DEFAULT_PROFILE, PROFILES, Profile, Scenario, load_profile


def test_the_folder_and_the_registry_agree():
    folder = resources.files("swarmtag.sim.config") / "presets"
    shipped = sorted(p.name for p in folder.iterdir() if p.name.endswith(".toml"))
    assert shipped == sorted(PROFILES.values())
    assert DEFAULT_PROFILE in PROFILES
    for name in PROFILES:
        assert load_profile(name).name == name


def test_the_base_profile_is_the_scenario_defaults():
    assert load_profile("base").scenario() == Scenario()


def test_profiles_leave_the_arena_to_the_scaling_rule():
    for name in PROFILES:
        values = load_profile(name).values
        assert "arena" not in values
        assert {"robots", "carriers", "ticks"}.isdisjoint(values)


def test_later_layers_win_over_the_profile():
    profile = load_profile("base")
    scenario = profile.scenario({"tick": 0.05, "camera": {"range": 2.0}}, {"camera.range": 3.0})
    assert (scenario.tick, scenario.camera.range) == (0.05, 3.0)
    assert scenario.timing == Scenario().timing


def test_a_profile_file_by_path(tmp_path: Path):
    path = tmp_path / "mine.toml"
    path.write_text('tick = 0.05\n[profile]\nname = "mine"\n[camera]\nrange = 2.5\n')
    profile = load_profile(path)
    assert (profile.name, profile.values) == ("mine", {"tick": 0.05, "camera": {"range": 2.5}})
    assert load_profile(str(path)).scenario().camera.range == 2.5


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("tick = 0.05\n", r"\[profile\] with name"),
        ('[profile]\nname = "x"\ncolour = 1\n', r"profile\.colour: unknown key"),
        ('[profile]\nname = "x"\n[camera]\nrang = 1\n', r"camera\.rang: unknown key"),
        ('tick = -1.0\n[profile]\nname = "x"\n', r"tick: -1\.0 is not a number in \[1e-06, 3600\]"),
    ],
)
def test_bad_profile_files_are_refused_naming_file_and_key(tmp_path, text, message):
    path = tmp_path / "bad.toml"
    path.write_text(text)
    with pytest.raises(ConfigError, match=message) as caught:
        load_profile(path)
    assert str(path) in str(caught.value)


def test_an_unknown_shipped_name_lists_the_shipped_ones():
    with pytest.raises(ConfigError, match="no such shipped profile"):
        load_profile("paper")


def test_to_mapping_round_trips():
    profile = Profile(name="p", description="d", values={"camera": {"memory": 5.0}})
    assert Profile.from_mapping(profile.to_mapping()) == profile


def test_the_default_world_is_the_default_profile():
    default = Scenario.default(robots=5, carriers=10)
    assert default == load_profile(DEFAULT_PROFILE).scenario({"robots": 5, "carriers": 10})
    assert Scenario.default(profile="base") == Scenario()


def test_the_base_profile_reproduces_the_first_edition_results():
    # docs/simulator.md, first edition: controller selection, proximity, 100 runs of seed 0
    from swarmtag.analysis.kpis import condition_kpis, run_values
    from swarmtag.analysis.runs import ConditionRuns
    from swarmtag.policy import Proximity
    from swarmtag.sim import simulate

    result = simulate(Scenario.default(profile="base"), Proximity(), seed=0, runs=100)
    kpis = condition_kpis(run_values(ConditionRuns.from_log(result.carriers, "proximity")))
    assert kpis.p95_latency is not None
    assert kpis.mean_latency is not None
    assert kpis.throughput is not None
    assert (round(kpis.p95_latency), round(kpis.mean_latency)) == (3295, 1899)
    assert (round(kpis.throughput, 3), round(kpis.pa, 3)) == (1.367, 0.348)
    assert kpis.undelivered == 0
