"""The Dask runner: a two-worker LocalCluster gives byte-identical results to the local runner.

Each test's Dask work runs in a process of its own (spawned): a Dask client
leaves threads behind in the process that used it (its IO loop, its offload
pool), and a process with other threads running must not fork
(``swarmtag._beside.can_fork``), so the later tests of the same pytest
worker that test the forked drawing processes could not.
"""

from __future__ import annotations

import contextlib
import io
import multiprocessing
from collections.abc import Callable
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path
from typing import Any, TypeVar

import pytest

from swarmtag.errors import StudyError
from swarmtag.experiments import ResultsStore, run_study, study_key
from swarmtag.io import format_csv

from .helpers import small_study, write_study

distributed = pytest.importorskip("distributed")

R = TypeVar("R")


def in_fresh_process(work: Callable[..., R], *args: Any) -> R:
    """``work(*args)`` in a spawned process, its result (or its error) returned here."""
    with ProcessPoolExecutor(1, mp_context=multiprocessing.get_context("spawn")) as pool:
        return pool.submit(work, *args).result()


@contextlib.contextmanager
def cluster() -> Any:
    # The scheduler serves HTTP even without a dashboard, on 8787 unless told otherwise; a
    # second cluster (the other pytest worker's) then warns that the port is in use, which
    # fails the test: an ephemeral port on the loopback interface instead.
    with distributed.LocalCluster(
        n_workers=2, threads_per_worker=1, dashboard_address="127.0.0.1:0", processes=True
    ) as started:
        yield started


def stored(out_dir, study):
    with ResultsStore(out_dir / "results.duckdb", read_only=True) as store:
        key = study_key(study, "default")
        return (
            format_csv(store.load_log(key, study.conditions, study.runs)),
            format_csv(store.load_events(key, study.conditions, study.runs)),
        )


def _local_and_dask(tmp: Path) -> dict[str, Any]:
    study = small_study()
    local = run_study(study, out_dir=tmp / "local", workers=1)
    with cluster() as started:
        first = run_study(
            small_study(chunk_runs=1), out_dir=tmp / "dask", scheduler=started.scheduler_address
        )
        again = run_study(study, out_dir=tmp / "dask", scheduler=started.scheduler_address)
    return {
        "first": first.computed_runs,
        "again": (again.computed_runs, again.reused_runs),
        "stored": (stored(tmp / "dask", study), stored(tmp / "local", study)),
        "metrics": (
            first.metrics_paths["default"].read_bytes(),
            local.metrics_paths["default"].read_bytes(),
        ),
    }


def test_a_dask_cluster_gives_byte_identical_results(tmp_path):
    found = in_fresh_process(_local_and_dask, tmp_path)
    assert found["first"] == 12
    assert found["again"] == (0, 12)
    dask_stored, local_stored = found["stored"]
    assert dask_stored == local_stored
    dask_metrics, local_metrics = found["metrics"]
    assert dask_metrics == local_metrics


def test_workers_and_scheduler_exclude_each_other(tmp_path):
    with pytest.raises(StudyError, match="give workers or scheduler"):
        run_study(small_study(), out_dir=tmp_path, workers=2, scheduler="tcp://127.0.0.1:1")


def _unreachable(tmp: Path) -> None:
    import dask

    with dask.config.set({"distributed.comm.timeouts.connect": "1s"}):
        run_study(small_study(), out_dir=tmp, scheduler="tcp://127.0.0.1:9")


def test_an_unreachable_scheduler_is_a_study_error(tmp_path):
    with pytest.raises(
        StudyError, match=r"cannot reach a Dask scheduler at 'tcp://127\.0\.0\.1:9'"
    ):
        in_fresh_process(_unreachable, tmp_path)


def _cli_on_a_scheduler(tmp: Path) -> tuple[object, str]:
    from swarmtag.cli import main

    argv = ["study", "run", str(write_study(tmp)), "--out", str(tmp / "out"), "--quick"]
    out = io.StringIO()
    with cluster() as started, contextlib.redirect_stdout(out):
        try:
            main([*argv, "--scheduler", started.scheduler_address, "--no-progress"])
        except SystemExit as exited:
            return exited.code, out.getvalue()
    return None, out.getvalue()


def test_the_cli_runs_on_a_scheduler(tmp_path):
    code, out = in_fresh_process(_cli_on_a_scheduler, tmp_path)
    assert code == 0
    assert out.startswith("small: 4 runs computed, 0 reused from the store\n")
    assert (tmp_path / "out" / "small" / "default" / "metrics.json").is_file()
