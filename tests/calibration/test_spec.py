"""Target files: the layout, every refusal (one line naming file and key), the shipped ones."""

from __future__ import annotations

import tomllib
from importlib import resources
from pathlib import Path

import pytest

from swarmtag.analysis import METRICS
from swarmtag.calibration import (
    TARGETS,
    KpiTarget,
    Setup,
    load_baseline,
    parse_free_list,
    read_target_file,
    target_kpis,
    target_path,
)
from swarmtag.calibration.problem import CalibrationProblem
from swarmtag.errors import CalibrationError
from swarmtag.sim.config.profiles import PROFILES, load_profile, profile_path
from tests.calibration.helpers import SMALL_TARGETS

GOOD = """
[calibration]
name = "mine"
description = "my arena"
condition = "urgency:alpha=0.7"
seed = 3
free = ["tick=0.05:0.2"]
evaluations = 12

[[setups]]
name = "a"
runs = 4
scenario = { robots = 2, carriers = 5, timing = { lift = 2.0 } }
[setups.kpis]
p95_latency = { value = 100, ci = [90, 120] }
pa = { value = 0.3, ci = [0.2, 0.4], weight = 0 }

[[setups]]
name = "b"
runs = 2
[setups.kpis]
total_deliveries = { value = 10, ci = [10, 10], weight = 2.5 }
"""


def write(tmp_path: Path, text: str) -> Path:
    path = tmp_path / "targets.toml"
    path.write_text(text, encoding="utf-8")
    return path


def test_a_good_file_reads_every_key(tmp_path):
    targets = read_target_file(write(tmp_path, GOOD))
    assert (targets.name, targets.description, targets.condition, targets.seed) == (
        "mine",
        "my arena",
        "urgency:alpha=0.7",
        3,
    )
    assert (targets.free, targets.evaluations, targets.kind) == (("tick=0.05:0.2",), 12, "targets")
    a, b = targets.setups
    assert (a.name, a.runs, a.scenario) == (
        "a",
        4,
        {"robots": 2, "carriers": 5, "timing": {"lift": 2.0}},
    )
    assert a.kpis == (
        KpiTarget("p95_latency", value=100.0, low=90.0, high=120.0),
        KpiTarget("pa", value=0.3, low=0.2, high=0.4, weight=0.0),
    )
    assert (b.scenario, b.kpis) == (
        {},
        (KpiTarget("total_deliveries", value=10.0, low=10.0, high=10.0, weight=2.5),),
    )
    assert targets.source_digest == read_target_file(write(tmp_path, GOOD)).source_digest


def test_defaults_condition_seed_and_free(tmp_path):
    text = '[[setups]]\nname = "a"\nruns = 1\nkpis = { pa = { value = 0.3, ci = [0.2, 0.4] } }\n'
    targets = read_target_file(write(tmp_path, text))
    assert (targets.name, targets.condition, targets.seed, targets.free) == (
        None,
        "proximity",
        0,
        (),
    )
    assert (targets.evaluations, targets.time_unit) == (None, None)


def test_the_digest_follows_the_content_not_the_layout(tmp_path):
    first = read_target_file(write(tmp_path, GOOD))
    reformatted = read_target_file(write(tmp_path, "# a comment\n" + GOOD))
    changed = read_target_file(write(tmp_path, GOOD.replace("value = 100", "value = 101")))
    assert first.digest == reformatted.digest
    assert first.source_digest != reformatted.source_digest
    assert changed.digest != first.digest


def test_every_metric_of_the_analysis_is_a_target_name():
    assert set(METRICS) <= set(target_kpis())
    assert {"total_deliveries", "undelivered"} <= set(target_kpis())


@pytest.mark.parametrize(
    ("old", "new", "message"),
    [
        ('name = "mine"', 'name = "my profile"', "calibration.name: 'my profile' is not a name"),
        ("seed = 3", "seed = -1", "calibration.seed: -1 is not an integer"),
        ("seed = 3", "colour = 3", "calibration.colour: unknown key"),
        ('condition = "urgency:alpha=0.7"', 'condition = "nearest"', "calibration.condition: "),
        ("evaluations = 12", "evaluations = 0", "calibration.evaluations: 0 is not an integer"),
        ('free = ["tick=0.05:0.2"]', 'free = "tick=0.05:0.2"', "calibration.free: 'tick=0.05:0.2'"),
        ('name = "a"', 'name = "b"', "setups: set-up 'b' is named twice"),
        ("runs = 4", "runs = 0", "setups[0]: runs: 0 is not an integer in 1-10000"),
        ("runs = 4", "runs = 4.0", "setups[0]: runs: 4.0 is not an integer"),
        ("runs = 4", "repeats = 4", "setups[0]: setup.repeats: unknown key"),
        ("robots = 2,", "robbots = 2,", "setups[0]: scenario.robbots: unknown key"),
        ("p95_latency = {", "p96_latency = {", "setups[0]: kpis.p96_latency: unknown key"),
        ("ci = [90, 120]", "ci = [120, 90]", "p95_latency: value 100.0 lies outside its ci"),
        ("ci = [90, 120]", "ci = [90]", "setups[0]: p95_latency.ci: [90] is not a pair"),
        ("ci = [90, 120]", 'ci = [90, "x"]', "p95_latency.ci[1]: 'x' is not a finite number"),
        ("value = 100, ci = [90, 120]", "value = 100", "p95_latency: ci is missing"),
        ("value = 100,", "value = nan,", "p95_latency.value: nan is not a finite number"),
        ("weight = 2.5", "weight = -1", "total_deliveries.weight: -1.0 is not a number >= 0"),
        ("weight = 2.5", "tolerance = 2.5", "total_deliveries.tolerance: unknown key"),
    ],
)
def test_refusals_name_the_file_and_the_key(tmp_path, old, new, message):
    assert old in GOOD
    path = write(tmp_path, GOOD.replace(old, new, 1))
    with pytest.raises(CalibrationError) as error:
        read_target_file(path)
    text = str(error.value)
    assert text.startswith(f"{path}: ")
    assert message in text
    assert "\n" not in text


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("[calibration]\n", "setups: at least one [[setups]] table is needed"),
        ("setups = 3\n", "setups: at least one"),
        ("[extra]\n", "target file.extra: unknown key"),
        (
            '[[setups]]\nname = "a"\nruns = 1\n[setups.kpis]\npa = {value = 0.3, ci = [0, 1], weight = 0}\n',
            "every KPI has weight 0",
        ),
        ('[[setups]]\nname = "a"\nruns = 1\n[setups.kpis]\n', "setups[0]: kpis: a set-up needs"),
        ("[[setups]]\nruns = 1\n", "setups[0]: name is missing"),
    ],
)
def test_refusals_of_the_structure(tmp_path, text, message):
    with pytest.raises(CalibrationError, match=None) as error:
        read_target_file(write(tmp_path, text))
    assert message in str(error.value)


def test_missing_and_broken_files_are_one_line(tmp_path):
    with pytest.raises(CalibrationError, match="no such target file"):
        read_target_file(tmp_path / "none.toml")
    with pytest.raises(CalibrationError, match="not valid TOML"):
        read_target_file(write(tmp_path, "[calibration\n"))


def test_a_setup_needs_unique_kpis():
    target = KpiTarget("pa", value=0.3, low=0.2, high=0.4)
    with pytest.raises(CalibrationError, match="named twice"):
        Setup(name="a", runs=1, scenario={}, kpis=(target, target))


def test_registry_and_folder_agree():
    folder = resources.files("swarmtag.calibration") / "targets"
    files = {entry.name for entry in folder.iterdir() if entry.name.endswith(".toml")}
    assert files == set(TARGETS.values())


@pytest.mark.parametrize("name", list(TARGETS))
def test_shipped_targets_read_and_their_free_parameters_fit_the_base_profile(name):
    path = target_path(name)
    with path.open("rb") as handle:
        assert tomllib.load(handle)["calibration"]["name"] == name
    targets = load_baseline(name)
    assert (targets.source, targets.name, targets.condition) == (name, name, "proximity")
    # The base to recalibrate on: the shipped profile of that name, else the base model.
    if name in PROFILES and profile_path(name).is_file():
        profile, settings = load_profile(name), {}
    else:
        profile = load_profile("base")
        settings = {"time_unit": targets.time_unit} if targets.time_unit else {}
    # Builds every set-up's scenario at both bounds of every default free parameter.
    CalibrationProblem(
        targets=targets,
        profile=profile,
        free=parse_free_list(targets.free),
        settings=settings,
        model="test",
    )


def test_unknown_shipped_name_lists_the_shipped_ones():
    with pytest.raises(CalibrationError, match=r"no shipped baseline .*shipped: paper-sim, lab"):
        load_baseline("paper")


def test_a_target_file_by_path_and_condition_only_for_event_logs():
    assert load_baseline(str(SMALL_TARGETS)).source == str(SMALL_TARGETS)
    with pytest.raises(CalibrationError, match="--condition picks an event log's condition"):
        load_baseline(str(SMALL_TARGETS), condition="proximity")
