"""Running a study: plan chunks of missing runs, simulate them in parallel, store, summarise.

``run_study`` splits every (scale, condition) of a study into chunks of at
most ``study.chunk_runs`` consecutive runs, asks the results store which runs
are missing, simulates only those chunks (in worker processes on the local
cores, in this process with ``workers=1``, or on a Dask cluster), and writes each finished chunk
to the store from this process in one transaction. A study interrupted at any
moment therefore resumes where it stopped, and its results do not depend on
the number of workers, the chunk size or the interruptions: run ``i`` of seed
``S`` is the same alone or in any batch (``swarmtag.sim.simulate``), and the
store gives rows back in simulated order.

Output folder layout::

    DIR/results.duckdb                    the results store (every study, every run)
    DIR/<study>/progress.json             runs stored / total, rewritten after each chunk
    DIR/<study>/<scale>/metrics.json      summarize(...).to_json() of the scale

A warehouse scale's summaries cover the orders placed after its warm-up
(``kpi_log``); the stored runs keep every order.
"""

from __future__ import annotations

import contextlib
import dataclasses
import json
import os
import warnings
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from types import TracebackType
from typing import Any, Final, Self

from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeRemainingColumn

from swarmtag._atomic import atomic_write_bytes
from swarmtag._checks import (
    MAX_WORKERS,
    check_bool,
    check_instance,
    check_int,
    check_path_value,
    check_text,
    show,
)
from swarmtag._inputs import check_path
from swarmtag._resources import check_memory
from swarmtag.analysis import MetricsReport, summarize, trim_warmup
from swarmtag.analysis.resampling import bootstrap_memory
from swarmtag.errors import BackendFallback, ConfigError, StatisticsError, StudyError
from swarmtag.experiments.chunks import ChunkJob, ChunkResult, split_runs
from swarmtag.experiments.execute import run_dask, run_local
from swarmtag.experiments.spec import Scale, Study
from swarmtag.experiments.store import ResultsStore, RunKey
from swarmtag.io import CarrierLog
from swarmtag.policy import parse_policy
from swarmtag.sim.backends import REFERENCE, resolve_backend
from swarmtag.sim.runner import LOG_BYTES_PER_CARRIER

__all__ = [
    "QUICK_RESAMPLES",
    "STORE_NAME",
    "StudyResult",
    "check_study_memory",
    "kpi_log",
    "plan_chunks",
    "run_study",
    "study_key",
]

STORE_NAME: Final = "results.duckdb"
"""File name of the results store inside the output folder."""
QUICK_RESAMPLES: Final = 1000
"""Bootstrap resamples under ``quick`` (at most; a study asking fewer keeps its own)."""
JOB_BYTES: Final = 600
"""Memory of one planned chunk job (its key and run range) until it is done."""


def kpi_log(log: CarrierLog, scale: Scale) -> CarrierLog:
    """The rows a scale's KPIs cover: for a warehouse, the orders placed after its warm-up.

    Continuous operation is measured past its start-up transient
    (``swarmtag.analysis.window``); other scales keep every row. A warm-up
    that leaves a run without orders is a ``StudyError`` naming the scale.
    """
    check_instance("log", log, CarrierLog, error=StudyError)
    check_instance("scale", scale, Scale, error=StudyError)
    try:
        return trim_warmup(log, scale.kpi_warmup(log.time_unit))
    except StatisticsError as error:
        msg = f"scales.{scale.key}: warehouse.warmup: {error}"
        raise StudyError(msg) from None


def study_key(study: Study, scale: str) -> RunKey:
    """The store key of one scale of ``study``."""
    check_instance("study", study, Study, error=StudyError)
    check_text("scale", scale, error=StudyError)
    return RunKey(
        study=study.name,
        scale=scale,
        seed=study.seed,
        code_version=study.scale(scale).code_version
        + (f".rules-{study.rules_digest}" if study.policy_files else ""),
    )


def plan_chunks(
    study: Study,
    store: ResultsStore,
    *,
    quick: bool = False,
    backend: str | None = None,
    threads: int | None = None,
) -> list[ChunkJob]:
    """The chunks of runs ``study`` still needs, in (scale, condition, run) order.

    ``backend`` and ``threads`` go with every chunk (``swarmtag.sim.simulate``).
    """
    check_instance("study", study, Study, error=StudyError)
    check_instance("store", store, ResultsStore, error=StudyError)
    check_bool("quick", quick, error=StudyError)
    if backend is not None:
        check_text("backend", backend, error=StudyError)
    if threads is not None:
        check_int("threads", threads, low=1, high=MAX_WORKERS, error=StudyError)
    total = study.run_count(quick=quick)
    jobs: list[ChunkJob] = []
    for scale in study.scales:
        key = study_key(study, scale.key)
        for condition in study.conditions:
            missing = store.missing_runs(key, condition, range(total))
            jobs.extend(
                ChunkJob(
                    key=key,
                    scenario=scale.scenario,
                    condition=condition,
                    run_offset=offset,
                    runs=count,
                    backend=backend,
                    threads=threads,
                    rules=study.policy_files,
                )
                for offset, count in split_runs(missing, study.chunk_runs)
            )
    return jobs


@dataclass(frozen=True, kw_only=True)
class StudyResult:
    """What ``run_study`` did: where results went, runs computed and reused, metrics per scale."""

    study: str
    store: Path
    metrics_paths: dict[str, Path]
    metrics: dict[str, dict[str, Any]]
    computed_runs: int
    reused_runs: int
    reports: dict[str, MetricsReport] = field(default_factory=dict, compare=False)
    """The summaries behind ``metrics``, per scale (a report in the same process reuses them)."""
    runs: int = 0
    """Runs per condition the summaries cover."""
    resamples: int = 0
    """Bootstrap resamples of the summaries."""


def _cost(job: ChunkJob) -> int:
    """A rough cost of a chunk (run-ticks times bodies): the costliest are started first.

    Scheduling big chunks first keeps every worker busy until the end; the
    order changes no result.
    """
    scenario = job.scenario
    return job.runs * scenario.run_ticks * (scenario.robots + scenario.carriers)


def _write_progress(path: Path, done: int, total: int) -> None:
    atomic_write_bytes(path, json.dumps({"done": done, "total": total}).encode() + b"\n")


def check_study_memory(study: Study, runs: int, *, quick: bool = False) -> None:
    """Refuse a study whose logs or bootstrap (loaded per scale at the end) cannot fit in memory."""
    conditions = len(study.conditions)
    resamples = min(study.resamples, QUICK_RESAMPLES) if quick else study.resamples
    carriers = max(scale.scenario.carriers for scale in study.scales)
    width = runs * carriers
    jobs = len(study.scales) * conditions * -(-runs // study.chunk_runs)
    estimate = (
        conditions * width * LOG_BYTES_PER_CARRIER
        + JOB_BYTES * jobs
        + bootstrap_memory(resamples, conditions=conditions, width=width)
    )
    check_memory(
        f"study {study.name} ({runs} runs x {conditions} conditions, {resamples} resamples)",
        estimate,
        error=StudyError,
    )


class _Created:
    """Paths a run creates, removed again if it fails (Ctrl-C included): it leaves no trace.

    Those named by ``keep`` stay (the store and ``progress.json`` once they
    hold a stored chunk); folders are removed only if empty.
    """

    def __init__(self, *paths: Path) -> None:
        self._new = [path for path in paths if not path.exists()]
        self._kept: set[Path] = set()

    def keep(self, *paths: Path) -> None:
        self._kept.update(paths)

    def __enter__(self) -> Self:
        return self

    def __exit__(
        self,
        kind: type[BaseException] | None,
        error: BaseException | None,
        trace: TracebackType | None,
    ) -> None:
        if kind is None:
            return
        gone = [path for path in self._new if path not in self._kept]
        for path in gone:
            if path.is_file():
                path.unlink(missing_ok=True)
        for path in sorted(gone, key=lambda path: len(path.parts), reverse=True):
            with contextlib.suppress(OSError):  # absent, or not empty: kept
                path.rmdir()


def _prepare_folder(folder: Path, name: str) -> None:
    """The results folder and its study folder, or one line saying why they cannot be made."""
    if folder.exists() and not folder.is_dir():
        msg = f"--out: {str(folder)!r} is a file; give a folder"
        raise StudyError(msg)
    if not folder.parent.is_dir():
        msg = f"--out: folder {str(folder.parent)!r} does not exist"
        raise StudyError(msg)
    try:
        (folder / name).mkdir(parents=True, exist_ok=True)
        probe = folder / f".{name}.writable.tmp"
        try:
            probe.touch()
        finally:
            probe.unlink(missing_ok=True)
    except OSError as problem:
        msg = f"--out: {str(folder)!r} cannot be written ({problem.strerror})"
        raise StudyError(msg) from None


def _by_kernel(jobs: Sequence[ChunkJob]) -> tuple[list[ChunkJob], list[ChunkJob]]:
    """The jobs the compiled kernel runs, and the others on the reference backend, one thread.

    A rule of one's own or an allocator is Python (``Policy.compiled``): its
    chunks go to worker processes instead of this process's kernel threads,
    and the fallback is said once (``BackendFallback``).
    """
    compiled, python = [], []
    told: list[str] = []
    for job in jobs:
        if parse_policy(job.condition).compiled:
            compiled.append(job)
            continue
        if job.condition not in told:
            told.append(job.condition)
        python.append(dataclasses.replace(job, backend=REFERENCE.name, threads=None))
    if told:
        msg = (
            f"{', '.join(sorted(told))}: not compiled; their runs go to the reference backend "
            "in worker processes (the same results, slower: docs/performance.md)"
        )
        warnings.warn(msg, BackendFallback, stacklevel=3)
    return compiled, python


def check_run_options(
    *,
    quick: object,
    workers: object,
    scheduler: object,
    progress: object,
    backend: object,
) -> None:
    """The options ``run_study`` and ``reproduce`` share, checked at their entry."""
    check_bool("quick", quick, error=StudyError)
    check_bool("progress", progress, error=StudyError)
    if workers is not None:
        count = check_int("workers", workers, low=1, error=StudyError)
        if count > MAX_WORKERS:
            msg = f"workers: {show(workers)} is above the most allowed, {MAX_WORKERS}"
            raise StudyError(msg)
    if scheduler is not None:
        check_text("scheduler", scheduler, error=StudyError)
    if backend is not None:
        check_text("backend", backend, error=StudyError)


def _execution(
    study: Study, backend: str | None, scheduler: str | None, workers: int | None
) -> tuple[str | None, int | None]:
    """The backend and kernel threads of a study's chunks.

    Locally the backend is resolved here (the compiled one runs the chunks in
    this process on ``workers`` threads; worker processes run one thread
    each); a Dask worker resolves the default itself and runs one thread.
    """
    chosen = study.backend if backend is None else backend
    try:
        resolved = resolve_backend(chosen).name
    except ConfigError as error:
        raise StudyError(str(error)) from None
    if scheduler is not None:
        return chosen, 1
    return resolved, workers if resolved == "fast" else 1


def _summaries(
    study: Study, store: ResultsStore, study_dir: Path, runs: int, resamples: int
) -> tuple[dict[str, MetricsReport], dict[str, dict[str, Any]], dict[str, Path]]:
    """Each scale's summary of ``runs`` stored runs, its JSON, and its ``metrics.json``."""
    reports: dict[str, MetricsReport] = {}
    metrics: dict[str, dict[str, Any]] = {}
    paths: dict[str, Path] = {}
    for scale in study.scales:
        log = kpi_log(store.load_log(study_key(study, scale.key), study.conditions, runs), scale)
        report = summarize(log, baseline=study.baseline, n_resamples=resamples, seed=study.seed)
        reports[scale.key] = report
        metrics[scale.key] = report.to_json()
        path = study_dir / scale.key / "metrics.json"
        path.parent.mkdir(exist_ok=True)
        text = json.dumps(metrics[scale.key], indent=2, allow_nan=False) + "\n"
        atomic_write_bytes(path, text.encode())
        paths[scale.key] = path
    return reports, metrics, paths


def run_study(
    study: Study,
    *,
    out_dir: str | os.PathLike[str],
    quick: bool = False,
    workers: int | None = None,
    scheduler: str | None = None,
    progress: bool = False,
    backend: str | None = None,
    store: str | os.PathLike[str] | None = None,
) -> StudyResult:
    """Compute the runs of ``study`` missing from the store in ``out_dir``, then its metrics.

    ``workers`` processes (default ``os.cpu_count()``) simulate chunks, or
    the Dask distributed cluster whose scheduler is at ``scheduler``
    (``"tcp://host:8786"``); results are identical either way. With the
    compiled backend (``backend``, else the study's, else the default) the
    chunks run in this process, each on ``workers`` threads. ``quick``
    runs ``study.quick_runs`` per condition and at most ``QUICK_RESAMPLES``
    bootstrap resamples. ``store`` is the results store file, by default
    ``out_dir/results.duckdb``; a reproduction over several master seeds
    keeps every seed's runs in one store and each seed's outputs in a folder
    of their own.
    Returns where everything went; writes ``metrics.json`` per scale.
    """
    check_instance("study", study, Study, error=StudyError)
    check_run_options(
        quick=quick, workers=workers, scheduler=scheduler, progress=progress, backend=backend
    )
    check_path_value("out_dir", out_dir, error=StudyError)
    if store is not None:
        check_path_value("store", store, error=StudyError)
    if workers is not None and scheduler is not None:
        raise StudyError("workers: a Dask cluster has its own workers; give workers or scheduler")
    if workers is not None and workers < 1:
        msg = f"workers: {workers} is not an integer >= 1"
        raise StudyError(msg)
    job_backend, threads = _execution(study, backend, scheduler, workers)
    in_threads = job_backend == "fast" and scheduler is None
    folder = check_path(out_dir, what="--out", error=StudyError)
    check_path(folder / study.name / "progress.json", what="--out", error=StudyError)
    store_path = folder / STORE_NAME if store is None else Path(store)
    runs = study.run_count(quick=quick)
    check_study_memory(study, runs, quick=quick)
    study_dir = folder / study.name
    progress_path = study_dir / "progress.json"
    total = runs * len(study.conditions) * len(study.scales)
    stores = (store_path, store_path.with_name(f"{store_path.name}.wal"), progress_path)
    scale_dirs = [study_dir / scale.key for scale in study.scales]
    with _Created(folder, study_dir, *stores, *scale_dirs) as created:
        _prepare_folder(folder, study.name)
        with ResultsStore(store_path) as runs_store:
            jobs = sorted(
                plan_chunks(
                    study,
                    runs_store,
                    quick=quick,
                    backend=job_backend,
                    threads=threads,
                ),
                key=_cost,
                reverse=True,
            )
            todo = sum(job.runs for job in jobs)
            done = total - todo
            _write_progress(progress_path, done, total)
            columns = (
                TextColumn(study.name),
                BarColumn(),
                MofNCompleteColumn(),
                TextColumn("runs"),
                TimeRemainingColumn(),
            )
            with Progress(*columns, disable=not progress, transient=True) as bar:
                task = bar.add_task(study.name, total=total, completed=done)

                def store_chunk(job: ChunkJob, logs: ChunkResult) -> None:
                    nonlocal done
                    done += runs_store.write_chunk(job.key, *logs)
                    created.keep(*stores)  # they hold completed work now: the next run resumes
                    _write_progress(progress_path, done, total)
                    bar.update(task, completed=done)

                if scheduler is not None:
                    run_dask(jobs, scheduler, store_chunk)
                elif in_threads:
                    compiled, python = _by_kernel(jobs)
                    run_local(compiled, 1, store_chunk)  # each chunk's runs on the threads
                    run_local(python, workers or os.cpu_count() or 1, store_chunk)
                else:
                    run_local(jobs, workers or os.cpu_count() or 1, store_chunk)
            resamples = min(study.resamples, QUICK_RESAMPLES) if quick else study.resamples
            reports, metrics, paths = _summaries(study, runs_store, study_dir, runs, resamples)
    return StudyResult(
        study=study.name,
        store=store_path,
        metrics_paths=paths,
        metrics=metrics,
        computed_runs=todo,
        reused_runs=total - todo,
        reports=reports,
        runs=runs,
        resamples=resamples,
    )
