"""The Dask runner: a two-worker LocalCluster gives byte-identical results to the local runner."""

from __future__ import annotations

import pytest

from swarmtag.errors import StudyError
from swarmtag.experiments import ResultsStore, run_study, study_key
from swarmtag.io import format_csv

from .helpers import small_study

distributed = pytest.importorskip("distributed")


def stored(out_dir, study):
    with ResultsStore(out_dir / "results.duckdb", read_only=True) as store:
        key = study_key(study, "default")
        return (
            format_csv(store.load_log(key, study.conditions, study.runs)),
            format_csv(store.load_events(key, study.conditions, study.runs)),
        )


@pytest.fixture(scope="module")
def cluster():
    # The scheduler serves HTTP even without a dashboard, on 8787 unless told otherwise; a
    # second cluster (the other pytest worker's) then warns that the port is in use, which
    # fails the test: an ephemeral port on the loopback interface instead.
    with distributed.LocalCluster(
        n_workers=2, threads_per_worker=1, dashboard_address="127.0.0.1:0", processes=True
    ) as started:
        yield started


def test_a_dask_cluster_gives_byte_identical_results(tmp_path, cluster):
    study = small_study()
    local = run_study(study, out_dir=tmp_path / "local", workers=1)
    first = run_study(
        small_study(chunk_runs=1), out_dir=tmp_path / "dask", scheduler=cluster.scheduler_address
    )
    again = run_study(study, out_dir=tmp_path / "dask", scheduler=cluster.scheduler_address)
    assert first.computed_runs == 12
    assert (again.computed_runs, again.reused_runs) == (0, 12)
    assert stored(tmp_path / "dask", study) == stored(tmp_path / "local", study)
    dask_metrics = first.metrics_paths["default"].read_bytes()
    assert dask_metrics == local.metrics_paths["default"].read_bytes()


def test_workers_and_scheduler_exclude_each_other(tmp_path):
    with pytest.raises(StudyError, match="give workers or scheduler"):
        run_study(small_study(), out_dir=tmp_path, workers=2, scheduler="tcp://127.0.0.1:1")


def test_an_unreachable_scheduler_is_a_study_error(tmp_path):
    import dask

    with (
        dask.config.set({"distributed.comm.timeouts.connect": "1s"}),
        pytest.raises(StudyError, match=r"cannot reach a Dask scheduler at 'tcp://127\.0\.0\.1:9'"),
    ):
        run_study(small_study(), out_dir=tmp_path, scheduler="tcp://127.0.0.1:9")


def test_the_cli_runs_on_a_scheduler(tmp_path, cluster, capsys):
    from swarmtag.cli import main

    from .helpers import write_study

    argv = ["study", "run", str(write_study(tmp_path)), "--out", str(tmp_path / "out"), "--quick"]
    with pytest.raises(SystemExit) as exited:
        main([*argv, "--scheduler", cluster.scheduler_address, "--no-progress"])
    out, _ = capsys.readouterr()
    assert exited.value.code == 0
    assert out.startswith("small: 4 runs computed, 0 reused from the store\n")
    assert (tmp_path / "out" / "small" / "default" / "metrics.json").is_file()
