"""The runner: results independent of workers and chunking, resume computes only missing runs."""

from __future__ import annotations

import json

import pytest

from swarmtag.analysis import summarize
from swarmtag.errors import StudyError
from swarmtag.experiments import ResultsStore, plan_chunks, run_study, study_key
from swarmtag.io import CarrierLog, format_csv
from swarmtag.sim import simulate

from .helpers import small_study


def stored_csv(out_dir, study, runs) -> str:
    with ResultsStore(out_dir / "results.duckdb", read_only=True) as store:
        return format_csv(store.load_log(study_key(study, "default"), study.conditions, runs))


def direct_csv(study, runs) -> str:
    scenario = study.scales[0].scenario
    logs = [simulate(scenario, p, seed=study.seed, runs=runs).carriers for p in study.policies()]
    return format_csv(CarrierLog.concat(logs))


def test_parallel_and_serial_runs_are_byte_identical(tmp_path):
    study = small_study()
    serial = run_study(study, out_dir=tmp_path / "serial", workers=1)
    parallel = run_study(small_study(chunk_runs=4), out_dir=tmp_path / "parallel", workers=2)
    assert serial.computed_runs == parallel.computed_runs == 12
    expected = direct_csv(study, 6)
    assert stored_csv(tmp_path / "serial", study, 6) == expected
    assert stored_csv(tmp_path / "parallel", study, 6) == expected
    serial_json = serial.metrics_paths["default"].read_bytes()
    assert parallel.metrics_paths["default"].read_bytes() == serial_json
    assert json.loads(serial_json) == serial.metrics["default"]


def test_metrics_are_summarize_of_the_stored_log(tmp_path):
    study = small_study()
    result = run_study(study, out_dir=tmp_path, workers=1)
    with ResultsStore(tmp_path / "results.duckdb", read_only=True) as store:
        log = store.load_log(study_key(study, "default"), study.conditions, 6)
    report = summarize(log, baseline="proximity", n_resamples=50, seed=0)
    assert result.metrics["default"] == json.loads(json.dumps(report.to_json()))
    assert [c["runs"] for c in result.metrics["default"]["conditions"]] == [6, 6]


def test_a_rerun_computes_nothing_and_quick_runs_are_reused(tmp_path):
    study = small_study()
    quick = run_study(study, out_dir=tmp_path, quick=True, workers=1)
    assert (quick.computed_runs, quick.reused_runs) == (4, 0)
    assert [c["runs"] for c in quick.metrics["default"]["conditions"]] == [2, 2]
    full = run_study(study, out_dir=tmp_path, workers=2)
    assert (full.computed_runs, full.reused_runs) == (8, 4)
    again = run_study(study, out_dir=tmp_path, workers=2)
    assert (again.computed_runs, again.reused_runs) == (0, 12)
    assert again.metrics == full.metrics
    assert json.loads((tmp_path / "small" / "progress.json").read_text()) == {
        "done": 12,
        "total": 12,
    }


def test_plan_covers_only_missing_runs_in_chunks(tmp_path):
    study = small_study(runs=7, chunk_runs=3)
    key = study_key(study, "default")
    with ResultsStore(tmp_path / "results.duckdb") as store:
        proximity = next(iter(study.policies()))
        result = simulate(study.scales[0].scenario, proximity, seed=0, runs=2, run_offset=2)
        store.write_chunk(key, result.carriers, result.events)
        jobs = plan_chunks(study, store)
    spans = [(job.condition, job.run_offset, job.runs) for job in jobs]
    assert spans == [
        ("proximity", 0, 2), ("proximity", 4, 3),
        ("urgency:alpha=0.7", 0, 3), ("urgency:alpha=0.7", 3, 3), ("urgency:alpha=0.7", 6, 1),
    ]  # fmt: skip


def test_a_changed_scenario_is_computed_afresh(tmp_path):
    run_study(small_study(runs=2, quick_runs=1), out_dir=tmp_path, workers=1)
    changed = run_study(small_study(runs=2, quick_runs=1, ticks=140), out_dir=tmp_path, workers=1)
    assert changed.computed_runs == 4


def test_several_scales_get_their_own_metrics(tmp_path):
    study = small_study(runs=2, quick_runs=1, scales={"a": {"robots": 2}, "b": {"robots": 4}})
    result = run_study(study, out_dir=tmp_path, workers=2)
    assert set(result.metrics_paths) == {"a", "b"}
    assert result.metrics_paths["b"] == tmp_path / "small" / "b" / "metrics.json"
    assert result.metrics["a"] != result.metrics["b"]


def test_bad_options_are_refused(tmp_path):
    with pytest.raises(StudyError, match="workers: 0 is not an integer >= 1"):
        run_study(small_study(), out_dir=tmp_path, workers=0)
    with pytest.raises(StudyError, match="does not exist"):
        run_study(small_study(), out_dir=tmp_path / "no" / "such", workers=1)


def test_the_progress_bar_changes_nothing(tmp_path, capsys):
    study = small_study(runs=2, quick_runs=1)
    shown = run_study(study, out_dir=tmp_path / "shown", workers=1, progress=True)
    hidden = run_study(study, out_dir=tmp_path / "hidden", workers=1, progress=False)
    assert shown.metrics == hidden.metrics
    capsys.readouterr()


def test_backends_store_the_same_runs(tmp_path):
    # the reference in two worker processes, the compiled kernel on two threads in this process
    reference = run_study(small_study(backend="reference"), out_dir=tmp_path / "ref", workers=2)
    fast = run_study(small_study(backend="fast"), out_dir=tmp_path / "fast", workers=2)
    study = small_study()
    assert stored_csv(tmp_path / "ref", study, 6) == stored_csv(tmp_path / "fast", study, 6)
    assert reference.metrics == fast.metrics
    override = run_study(small_study(), out_dir=tmp_path / "over", workers=1, backend="reference")
    assert override.metrics == fast.metrics


def test_unknown_backends_are_refused(tmp_path):
    with pytest.raises(StudyError, match="backend: 'gpu' is not one of reference, fast"):
        small_study(backend="gpu")
    with pytest.raises(StudyError, match="backend"):
        run_study(small_study(), out_dir=tmp_path, workers=1, backend="gpu")
