"""``swarmtag reproduce``: every study at one or several master seeds, then the report.

With ``seeds=1`` each study runs at its own master seed (the ``seed`` of its
file) into ``out_dir``, as ``run_study`` lays it out, and ``out_dir/report.html``
collects them. With ``seeds=K`` each study also runs at ``seed + 1 .. seed +
K-1`` (``seeded_study``), seed by seed; all runs go to the one results store
``out_dir/results.duckdb`` (its key holds the master seed, so seeds never
mix, and an interrupted run resumes), and each further seed's outputs to a
folder of their own (``seed_folder``)::

    DIR/results.duckdb                every run of every seed
    DIR/<study>/...                   offset 0: the studies at their own seeds, as with K = 1
    DIR/seed+<j>/<study>/...          offset j: the studies at seed + j (metrics, tables, figures)
    DIR/seed+<j>/report.html          the report of offset j
    DIR/seeds.json, DIR/seeds.md      the directions over the K seeds (``robustness``)
    DIR/report.html                   offset 0's report, the seeds summary after its verdicts

Every seed's results are judged against ``directions`` (SPEC §6) as they
come in; only those small outcomes are kept, so memory does not grow with K.
"""

from __future__ import annotations

import dataclasses
import json
import os
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Final

from swarmtag._atomic import atomic_write_bytes
from swarmtag._checks import (
    MAX_SEED,
    check_instance,
    check_int,
    check_path_value,
    check_sequence,
    show,
)
from swarmtag._inputs import check_path
from swarmtag.errors import StudyError
from swarmtag.experiments.directions import DIRECTIONS, Direction
from swarmtag.experiments.report import StudyRecord, write_report, write_run_record
from swarmtag.experiments.robustness import ClaimSummary, Outcome, judge_study, robustness
from swarmtag.experiments.runner import (
    STORE_NAME,
    StudyResult,
    check_run_options,
    check_study_memory,
    run_study,
)
from swarmtag.experiments.seed_tables import (
    robustness_json,
    robustness_markdown,
    robustness_section,
)
from swarmtag.experiments.spec import Study

__all__ = [
    "MAX_SEEDS",
    "SEEDS_JSON",
    "SEEDS_MARKDOWN",
    "Reproduction",
    "StudyRun",
    "reproduce",
    "seed_folder",
    "seeded_study",
]

MAX_SEEDS: Final = 100
"""Most master seeds one reproduction runs: each is a full run of every study (for the five of
SPEC §6 about 30 s and 12 MiB of results on two cores), so more is a slip, not a plan."""
SEEDS_JSON: Final = "seeds.json"
"""File of the directions over the seeds, in ``out_dir`` (with ``seeds > 1``)."""
SEEDS_MARKDOWN: Final = "seeds.md"
"""The same as Markdown tables."""


def seeded_study(study: Study, offset: int) -> Study:
    """``study`` at master seed ``study.seed + offset``: the seed rule of ``reproduce``."""
    check_instance("study", study, Study, error=StudyError)
    offset = check_int("offset", offset, low=0, high=MAX_SEED - study.seed, error=StudyError)
    return dataclasses.replace(study, seed=study.seed + offset)


def seed_folder(out_dir: str | os.PathLike[str], offset: int) -> Path:
    """Where the outputs of seed offset ``offset`` go: ``out_dir`` itself for 0."""
    out_dir = check_path_value("out_dir", out_dir, error=StudyError)
    offset = check_int("offset", offset, low=0, high=MAX_SEED, error=StudyError)
    return Path(out_dir) if offset == 0 else Path(out_dir) / f"seed+{offset}"


def check_seeds(studies: Sequence[Study], seeds: int, *, quick: bool = False) -> None:
    """Refuse ``seeds`` before any work: out of ``1..MAX_SEEDS``, a seed past ``MAX_SEED``, memory.

    Seeds run one after another, so one study's memory bounds them all.
    """
    check_int("--seeds", seeds, low=1, high=MAX_SEEDS, error=StudyError)
    for study in studies:
        if study.seed + seeds - 1 > MAX_SEED:
            msg = (
                f"--seeds {seeds}: study {study.name} starts at master seed {study.seed}, "
                f"and seeds stop at {MAX_SEED}"
            )
            raise StudyError(msg)
        check_study_memory(study, study.run_count(quick=quick), quick=quick)


@dataclass(frozen=True, kw_only=True)
class StudyRun:
    """One study at one master seed, done: what ``swarmtag reproduce`` prints for it."""

    study: str
    seed: int
    offset: int
    computed_runs: int
    reused_runs: int
    wall_time_s: float


@dataclass(frozen=True, kw_only=True)
class Reproduction:
    """What ``reproduce`` did: the report, every study run, and the directions over the seeds."""

    report: Path
    seeds: int
    runs: tuple[StudyRun, ...]
    robustness: tuple[ClaimSummary, ...]
    """One summary per direction and study; empty with one seed."""
    summary_files: tuple[Path, ...]
    """``seeds.json`` and ``seeds.md``; empty with one seed."""


@dataclass(frozen=True, kw_only=True)
class _Execution:
    """How every study is run: ``run_study``'s options, the same for every seed."""

    quick: bool
    workers: int | None
    scheduler: str | None
    progress: bool
    backend: str | None


def _run_seed(
    studies: Sequence[Study],
    *,
    offset: int,
    folder: Path,
    store: Path,
    execution: _Execution,
    on_study: Callable[[StudyRun], None],
) -> tuple[list[StudyResult], list[StudyRun]]:
    """Run every study at seed offset ``offset`` into ``folder``; record each run's wall time."""
    results, runs = [], []
    for study in studies:
        begin = time.perf_counter()
        result = run_study(
            study,
            out_dir=folder,
            quick=execution.quick,
            workers=execution.workers,
            scheduler=execution.scheduler,
            progress=execution.progress,
            backend=execution.backend,
            store=store,
        )
        wall = time.perf_counter() - begin
        record = StudyRecord(
            wall_time_s=wall,
            quick=execution.quick,
            computed_runs=result.computed_runs,
            reused_runs=result.reused_runs,
        )
        write_run_record(folder, study, record)
        run = StudyRun(
            study=study.name,
            seed=study.seed,
            offset=offset,
            computed_runs=result.computed_runs,
            reused_runs=result.reused_runs,
            wall_time_s=wall,
        )
        on_study(run)
        results.append(result)
        runs.append(run)
    return results, runs


def reproduce(
    studies: Sequence[Study],
    *,
    out_dir: str | os.PathLike[str],
    seeds: int = 1,
    quick: bool = False,
    workers: int | None = None,
    scheduler: str | None = None,
    progress: bool = False,
    backend: str | None = None,
    directions: Sequence[Direction] = DIRECTIONS,
    on_study: Callable[[StudyRun], None] | None = None,
) -> Reproduction:
    """Run ``studies`` (resuming what the store holds) at ``seeds`` master seeds; write the report.

    Study ``s`` runs at ``s.seed + j`` for ``j = 0 .. seeds-1`` (see the
    module docstring for the folders); ``quick``, ``workers``,
    ``scheduler``, ``progress`` and ``backend`` are ``run_study``'s.
    ``on_study`` hears of each study run as it finishes. With ``seeds > 1``
    every seed's results are judged against ``directions`` and the summary
    is written to ``seeds.json``, ``seeds.md`` and ``report.html`` (after the
    verdicts on the first seed, which every report opens with).
    Everything that can be refused (``seeds``, a seed past the largest,
    memory) is refused before the first run.
    """
    studies = check_sequence("studies", studies, error=StudyError)
    for study in studies:
        check_instance("studies", study, Study, error=StudyError)
    directions = check_sequence("directions", directions, error=StudyError)
    for direction in directions:
        check_instance("directions", direction, Direction, error=StudyError)
    hook: object = on_study  # checked at run time: a library entry point
    if hook is not None and not callable(hook):
        msg = f"on_study: {show(hook)} is not callable"
        raise StudyError(msg)
    check_run_options(
        quick=quick, workers=workers, scheduler=scheduler, progress=progress, backend=backend
    )
    out_dir = check_path_value("out_dir", out_dir, error=StudyError)
    folder = check_path(out_dir, what="--out", error=StudyError)
    check_seeds(studies, seeds, quick=quick)
    store = folder / STORE_NAME
    execution = _Execution(
        quick=quick, workers=workers, scheduler=scheduler, progress=progress, backend=backend
    )
    hear = on_study or (lambda run: None)
    outcomes: list[Outcome] = []
    runs: list[StudyRun] = []
    first: list[StudyResult] = []
    for offset in range(seeds):
        specs = [seeded_study(study, offset) for study in studies]
        target = seed_folder(folder, offset)
        results, done = _run_seed(
            specs, offset=offset, folder=target, store=store, execution=execution, on_study=hear
        )
        runs += done
        if seeds > 1:
            for spec, result in zip(specs, results, strict=True):
                outcomes += judge_study(spec.name, spec.seed, result.reports, directions)
        if offset == 0:
            first = results  # the main report, written last, reuses their summaries
        else:
            write_report(target, specs, computed=results, store=store, directions=directions)
    if seeds == 1:
        report = write_report(folder, studies, computed=first, store=store, directions=directions)
        return Reproduction(
            report=report, seeds=1, runs=tuple(runs), robustness=(), summary_files=()
        )
    summaries = robustness(outcomes, directions)
    used = {study.name: [study.seed + offset for offset in range(seeds)] for study in studies}
    files = (folder / SEEDS_JSON, folder / SEEDS_MARKDOWN)
    data = robustness_json(summaries, seeds=used)
    atomic_write_bytes(files[0], (json.dumps(data, indent=2, allow_nan=False) + "\n").encode())
    atomic_write_bytes(files[1], robustness_markdown(summaries, seeds=used).encode())
    report = write_report(
        folder,
        studies,
        computed=first,
        store=store,
        sections=[robustness_section(summaries, seeds=used)],
        directions=directions,
    )
    return Reproduction(
        report=report, seeds=seeds, runs=tuple(runs), robustness=summaries, summary_files=files
    )
