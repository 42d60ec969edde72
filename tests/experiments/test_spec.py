"""Study files: the shipped studies of SPEC §6, the registry, user files and named errors."""

from __future__ import annotations

from importlib import resources
from pathlib import Path

import pytest

from swarmtag.errors import StudyError
from swarmtag.experiments import REPRODUCED, STUDIES, Study, load_study, study_path
from swarmtag.policy import Policy
from swarmtag.sim import Scenario

from .helpers import SMALL, SMALL_TOML, small_study, write_study


def test_registry_and_folder_agree():
    folder = resources.files("swarmtag.experiments") / "studies"
    files = {entry.name for entry in folder.iterdir() if entry.name.endswith(".toml")}
    assert files == set(STUDIES.values())
    for name, file in STUDIES.items():
        assert Path(file).stem == name


@pytest.mark.parametrize("name", list(STUDIES))
def test_every_shipped_study_loads_and_builds(name):
    study = load_study(name)
    assert study.name == name
    assert study == load_study(study_path(name))
    assert study.baseline in study.conditions
    assert 1 <= study.quick_runs <= study.runs
    assert all(isinstance(policy, Policy) for policy in study.policies())
    assert [p.name for p in study.policies()] == list(study.conditions)
    for scale in study.scales:
        assert isinstance(scale.scenario, Scenario)
        assert Scenario.from_mapping(scale.scenario.to_mapping()) == scale.scenario
        assert scale.scenario.urgency.model == study.urgency


SPEC_TABLE = {
    # name: (conditions, runs, urgency, [(robots, carriers, run ticks)])
    "preliminary-sweep": (
        [f"weighted:w={w / 10!r}" for w in range(11)], 100, "growing", [(3, 7, 3000)]
    ),
    "candidate-alphas": (
        ["urgency:alpha=0.3", "urgency:alpha=0.5", "urgency:alpha=0.7", "urgency:alpha=0.9"],
        100, "growing", [(3, 7, 3000)],
    ),
    "controller-selection": (
        ["proximity", "urgency:alpha=0.7", "urgency:alpha=3.0", "urgency:alpha=9.0"],
        100, "growing", [(3, 7, 3000)],
    ),
    "physical-style": (
        ["proximity", "urgency:alpha=0.7", "urgency:alpha=3.0", "urgency:alpha=9.0"],
        16, "static", [(3, 7, 6000)],
    ),
    "scalability": (
        ["proximity", "urgency:alpha=0.7"], 21, "growing",
        [(5, 10, 3000), (10, 20, 6000), (20, 40, 12000)],
    ),
}  # fmt: skip


@pytest.mark.parametrize("name", list(SPEC_TABLE))
def test_shipped_studies_match_the_spec_table(name):
    conditions, runs, urgency, scales = SPEC_TABLE[name]
    study = load_study(name)
    assert list(study.conditions) == conditions
    assert study.runs == runs
    assert study.urgency == urgency
    assert [
        (s.scenario.robots, s.scenario.carriers, s.scenario.run_ticks) for s in study.scales
    ] == scales


def test_spec_table_covers_the_reproduced_studies():
    assert list(SPEC_TABLE) == list(REPRODUCED)
    assert set(REPRODUCED) <= set(STUDIES)


def test_a_user_file_loads_by_path(tmp_path):
    path = write_study(tmp_path)
    study = load_study(path)
    assert study == small_study()
    assert load_study(str(path)) == study
    assert study.scale("default").scenario.ticks == 150


def test_scales_merge_onto_the_scenario_and_set_their_run_length():
    study = small_study(
        scenario={"carriers": 7, "detection_radius": 2.0},
        scales={"a": {"robots": 2}, "b": {"robots": 4, "ticks": 90}},
    )
    a, b = study.scales
    assert (a.key, a.scenario.robots, a.scenario.ticks, a.scenario.detection_radius) == (
        "a", 2, 150, 2.0,
    )  # fmt: skip
    assert (b.scenario.robots, b.scenario.ticks) == (4, 90)
    assert a.code_version != b.code_version


def test_static_urgency_sets_the_time_limit():
    study = small_study(urgency="static", ticks=900)
    scenario = study.scales[0].scenario
    assert scenario.urgency.model == "static"
    assert scenario.run_ticks == 900


def test_code_version_follows_the_scenario():
    base = small_study().scales[0].code_version
    assert small_study().scales[0].code_version == base
    assert small_study(ticks=151).scales[0].code_version != base
    assert small_study(runs=9).scales[0].code_version == base


def test_baseline_defaults_to_the_first_condition():
    data = {key: value for key, value in SMALL.items() if key != "baseline"}
    assert Study.from_mapping(data).baseline == "proximity"


@pytest.mark.parametrize(
    ("change", "message"),
    [
        (
            'conditions = ["proximity", "urgency:alpha=0.7", "urgency:alpa=3"]',
            "study.toml: conditions[2]: 'urgency:alpa=3' is not a condition",
        ),
        ('conditions = ["proximity", "proximity"]', "conditions[1]: 'proximity' repeats"),
        ("conditions = []", "conditions: [] is not a non-empty list"),
        ("conditions = [3]", "conditions[0]: 3 is not a condition name"),
        ("runs = 0", "study.toml: runs: 0 is not an integer in 1-9007199254740992"),
        ('runs = "many"', "runs: 'many' is not an integer in 1-9007199254740992"),
        ("quick_runs = 7", "quick_runs: 7 is more than runs (6)"),
        ("seed = -1", "seed: -1 is not an integer in 0-9223372036854775807"),
        ("ticks = true", "ticks: True is not an integer in 1-100000000"),
        ('urgency = "rising"', "urgency: 'rising' is not one of growing, static"),
        ('baseline = "weighted:w=0.5"', "baseline: 'weighted:w=0.5' is not one of the conditions"),
        ("runz = 3", "runz: unknown key; a study has keys"),
        ('name = "../escape"', "name: '../escape' may hold only letters, digits"),
    ],
)
def test_bad_top_level_keys_are_named(tmp_path, change, message):
    key = change.split(" = ")[0]
    lines = [line for line in SMALL_TOML.splitlines() if not line.startswith(f"{key} =")]
    path = write_study(tmp_path, change + "\n" + "\n".join(lines) + "\n")
    with pytest.raises(StudyError) as error:
        load_study(path)
    assert message in str(error.value)
    assert str(error.value).startswith("study.toml: ")


@pytest.mark.parametrize(
    ("extra", "message"),
    [
        ("[scenario.arena]\nsise = 4.0\n", "scenario: arena.sise: unknown key"),
        ("[scenario]\nrobots = 0\n", "robots: 0"),
        ("[scales.big]\nrobots = 0\n", "scales.big: robots: 0"),
        ("[scales.big]\nticks = 0\n", "scales.big.ticks: 0 is not an integer in 1-100000000"),
        ("[scales]\n", "scales: the table is empty"),
        ('[scales."a b"]\nrobots = 2\n', "scales.a b: 'a b' may hold only letters"),
        ("[scenario.urgency]\nmodel = 'static'\n", "scenario.urgency.model: set the study's"),
    ],
)
def test_bad_scenario_keys_are_named(tmp_path, extra, message):
    text = SMALL_TOML.split("[scenario]")[0] + extra
    path = write_study(tmp_path, text)
    with pytest.raises(StudyError) as error:
        load_study(path)
    assert message in str(error.value)


def test_scenario_may_not_set_the_run_length(tmp_path):
    path = write_study(tmp_path, SMALL_TOML + "ticks = 10\n")
    with pytest.raises(StudyError, match=r"scenario\.ticks: set the study's top-level 'ticks'"):
        load_study(path)


def test_missing_required_key_is_named(tmp_path):
    text = "\n".join(line for line in SMALL_TOML.splitlines() if not line.startswith("runs ="))
    with pytest.raises(StudyError, match=r"study\.toml: runs: missing"):
        load_study(write_study(tmp_path, text))


def test_unreadable_files_are_study_errors(tmp_path):
    with pytest.raises(StudyError, match="no such study file"):
        load_study(tmp_path / "absent.toml")
    with pytest.raises(StudyError, match="not valid TOML"):
        load_study(write_study(tmp_path, "name = \n"))
    with pytest.raises(StudyError, match="no such shipped study"):
        load_study("controller-selectoin")


def test_unknown_scale_is_named():
    with pytest.raises(StudyError, match=r"scale 'huge': not in study 'small' \(scales: "):
        small_study().scale("huge")


def test_direct_construction_is_validated_and_canonical():
    scale = small_study().scales[0]
    study = Study(name="direct", conditions=("urgency:alpha=3",), scales=(scale,), runs=2,
                  quick_runs=1)  # fmt: skip
    assert study.conditions == ("urgency:alpha=3.0",)
    assert study.baseline == "urgency:alpha=3.0"
    with pytest.raises(StudyError, match=r"scales\.default: the key is used twice"):
        Study(name="direct", conditions=("proximity",), scales=(scale, scale), runs=2,
              quick_runs=1)  # fmt: skip
    with pytest.raises(StudyError, match="urgency: 'rising' is not one of"):
        Study(name="direct", conditions=("proximity",), scales=(scale,), runs=2, quick_runs=1,
              urgency="rising")  # fmt: skip


def test_code_version_changes_with_the_model_source(monkeypatch, tmp_path):
    import shutil

    from swarmtag.experiments import spec

    scale = load_study("controller-selection").scales[0]
    version, rest = scale.code_version.split("+")
    assert version == spec.__version__
    scenario_hash, model_hash = rest.split(".")
    assert len(scenario_hash) == len(model_hash) == 12
    assert model_hash == spec.model_digest()
    # A copy of the package: a byte changed in the model changes the digest, in a picture not.
    import swarmtag._sources as sources

    root = tmp_path / "swarmtag"
    shutil.copytree(Path(spec.__file__).resolve().parents[1], root)
    monkeypatch.setattr(sources, "PACKAGE_ROOT", root)
    monkeypatch.setattr(spec, "PACKAGE_ROOT", root)
    try:
        for changed, same in (("sim/outputs/render.py", True), ("sim/model/step.py", False)):
            source = root / changed
            source.write_bytes(source.read_bytes() + b"\n# changed\n")
            spec.model_digest.cache_clear()
            assert (spec.model_digest() == model_hash) is same, changed
        assert all(root in path.parents for path in spec.model_sources())
    finally:
        spec.model_digest.cache_clear()
