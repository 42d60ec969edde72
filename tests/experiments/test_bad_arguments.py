"""The public study functions refuse wrong arguments with ``StudyError`` (issue 35, item 7).

Each call here once escaped as a bare ``TypeError``, ``AttributeError`` or
``ValueError`` (``os.fspath``, an unhashable key, ``int + None``, the truth
value of an array), or was let through to fail later.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from swarmtag.data import example_trial_path
from swarmtag.errors import StoreError, StudyError
from swarmtag.experiments import (
    ResultsStore,
    Study,
    kpi_log,
    load_study,
    plan_chunks,
    read_study_file,
    reproduce,
    run_study,
    seed_folder,
    seeded_study,
    simulate_chunk,
    split_runs,
    study_key,
    study_path,
)
from swarmtag.io import read_event_log
from tests.experiments.helpers import small_study

STUDY = small_study()
HUGE = pytest.param(10**5000, id="10**5000")
BAD_PATHS = [None, 3, math.nan, ["a.toml"], {}, "", "a\0.toml", HUGE]
NOT_OBJECTS = [None, 1.5, "small", [], {}, np.array([1.0])]


@pytest.mark.parametrize("path", BAD_PATHS)
@pytest.mark.parametrize(
    ("read", "name"), [(read_study_file, "path"), (load_study, "name_or_path")]
)
def test_study_readers_refuse_what_is_no_path(read, name, path):
    with pytest.raises(StudyError, match=rf"^{name}: .* is not a path"):
        read(path)


@pytest.mark.parametrize("name", [None, 3, [], {}, HUGE])
def test_study_path_refuses_a_name_that_is_no_string(name):
    with pytest.raises(StudyError, match=r"^name: .* is not a string"):
        study_path(name)


@pytest.mark.parametrize("data", [None, 1.5, "small", ["name"], HUGE])
def test_from_mapping_refuses_data_that_is_no_table(data):
    with pytest.raises(StudyError, match=r"^data: .* is not a mapping"):
        Study.from_mapping(data)


@pytest.mark.parametrize(
    ("arguments", "name"),
    [({"source": 3}, "source"), ({"source": np.array([])}, "source"), ({"base": "."}, "base")],
)
def test_from_mapping_refuses_a_bad_source_or_base(arguments, name):
    with pytest.raises(StudyError, match=rf"^{name}: "):
        Study.from_mapping({"name": "x"}, **arguments)


@pytest.mark.parametrize("study", NOT_OBJECTS)
@pytest.mark.parametrize(
    "call",
    [
        lambda study: seeded_study(study, 1),
        lambda study: study_key(study, "default"),
        lambda study: run_study(study, out_dir="out"),
    ],
)
def test_study_arguments_must_be_studies(call, study):
    with pytest.raises(StudyError, match=r"^study: .* is not a Study"):
        call(study)


@pytest.mark.parametrize("offset", [None, -1, 1.0, "1", math.nan, np.array([]), 2**63, HUGE])
def test_seeded_study_and_seed_folder_refuse_a_bad_offset(offset):
    with pytest.raises(StudyError, match=r"^offset: "):
        seeded_study(STUDY, offset)
    with pytest.raises(StudyError, match=r"^offset: "):
        seed_folder("out", offset)


@pytest.mark.parametrize("out_dir", BAD_PATHS)
def test_seed_folder_refuses_what_is_no_path(out_dir):
    with pytest.raises(StudyError, match=r"^out_dir: .* is not a path"):
        seed_folder(out_dir, 0)


@pytest.mark.parametrize("scale", [None, 3, np.array([]), ["default"]])
def test_study_key_refuses_a_scale_that_is_no_string(scale):
    with pytest.raises(StudyError, match=r"^scale: .* is not a string"):
        study_key(STUDY, scale)


def test_kpi_log_refuses_arguments_of_another_kind():
    log = read_event_log(example_trial_path())
    with pytest.raises(StudyError, match=r"^log: .* is not a CarrierLog"):
        kpi_log(None, STUDY.scales[0])
    with pytest.raises(StudyError, match=r"^scale: .* is not a Scale"):
        kpi_log(log, "default")


@pytest.mark.parametrize(
    ("arguments", "name"),
    [
        ({"store": None}, "store"),
        ({"store": "results.duckdb"}, "store"),
        ({"quick": np.array([])}, "quick"),
        ({"quick": 1}, "quick"),
        ({"backend": 3}, "backend"),
        ({"threads": 0}, "threads"),
        ({"threads": "2"}, "threads"),
    ],
)
def test_plan_chunks_refuses_bad_arguments(arguments, name, tmp_path):
    with ResultsStore(tmp_path / "results.duckdb") as store:
        given = {"study": STUDY, "store": store, **arguments}
        with pytest.raises(StudyError, match=rf"^{name}: "):
            plan_chunks(given.pop("study"), given.pop("store"), **given)


@pytest.mark.parametrize(
    ("arguments", "name"),
    [
        ({"workers": "2"}, "workers"),
        ({"workers": math.nan}, "workers"),
        ({"workers": 0}, "workers"),
        ({"workers": 10**6}, "workers"),
        ({"quick": "yes"}, "quick"),
        ({"progress": None}, "progress"),
        ({"scheduler": 8786}, "scheduler"),
        ({"backend": ["fast"]}, "backend"),
        ({"out_dir": "a\0b"}, "out_dir"),
        ({"out_dir": None}, "out_dir"),
        ({"store": 3}, "store"),
    ],
)
def test_run_study_refuses_bad_options_before_any_work(arguments, name, tmp_path):
    given = {"out_dir": tmp_path, **arguments}
    with pytest.raises(StudyError, match=rf"^{name}: "):
        run_study(STUDY, **given)
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize(
    ("arguments", "name"),
    [
        ({"studies": STUDY}, "studies"),
        ({"studies": ["small"]}, "studies"),
        ({"directions": [None]}, "directions"),
        ({"on_study": 3}, "on_study"),
        ({"workers": "2"}, "workers"),
        ({"quick": None}, "quick"),
        ({"out_dir": 3}, "out_dir"),
    ],
)
def test_reproduce_refuses_bad_arguments_before_any_work(arguments, name, tmp_path):
    given = {"studies": [STUDY], "out_dir": tmp_path, **arguments}
    with pytest.raises(StudyError, match=rf"^{name}: "):
        reproduce(given.pop("studies"), **given)
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("job", NOT_OBJECTS)
def test_simulate_chunk_refuses_what_is_no_job(job):
    with pytest.raises(StudyError, match=r"^job: .* is not a ChunkJob"):
        simulate_chunk(job)


@pytest.mark.parametrize(
    ("runs", "size", "name"),
    [
        (5, 2, "runs"),
        ([0, 1.5], 2, "runs"),
        ([0, -1], 2, "runs"),
        ([0, None], 2, "runs"),
        ([0, 1], 0, "size"),
        ([0, 1], "2", "size"),
        ([0, 1], math.inf, "size"),
    ],
)
def test_split_runs_refuses_bad_arguments_when_called(runs, size, name):
    with pytest.raises(StudyError, match=rf"^{name}: "):
        split_runs(runs, size)  # refused at the call, not when the spans are first read


@pytest.mark.parametrize("path", [None, 3, "", "a\0.duckdb", ["x"]])
def test_results_store_refuses_what_is_no_path(path, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    with pytest.raises(StoreError, match=r"^path: .* is not a path"):
        ResultsStore(path)
    assert list(tmp_path.iterdir()) == []


def test_results_store_refuses_a_read_only_that_is_no_bool(tmp_path):
    with pytest.raises(StoreError, match=r"^read_only: "):
        ResultsStore(tmp_path / "x.duckdb", read_only="yes")


def test_good_calls_still_work(tmp_path):
    assert list(split_runs(np.array([0, 1, 2, 5]), 2)) == [(0, 2), (2, 1), (5, 1)]
    assert seeded_study(STUDY, 2).seed == STUDY.seed + 2
    assert seed_folder(Path("out"), 1) == Path("out/seed+1")
    assert load_study(study_path("scalability")).name == "scalability"
