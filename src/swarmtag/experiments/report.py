"""The reproduction report: every study's tables and figures from the results store, one HTML file.

For each study and swarm size the runs stored in ``DIR/results.duckdb`` are
summarised again (the same seed gives the same numbers), and written next to
the study's metrics: the event logs (``carriers.csv``, ``events.csv``, or
Parquet), ``tables.md`` and ``tables.tex`` (values with 95 % CIs,
differences with CIs and both p-values, the censoring-aware latencies, the
choice statistics from the stored event tables) and ``figures/`` (PA curves and
latency curves with bands, latency per urgency level, the parameter sweep
where a study sweeps one policy). Studies with several swarm sizes also get
the scalability table (relative changes signed so that positive is better)
and one panel set per size; a study with ``ranking = true`` gets its
conditions ranked per size (``ranking.md``) and a Pareto figure
(``pareto.png``). ``DIR/report.html`` collects everything with the
study parameters, the code version and the wall time of the last run: it
opens with the verdict on every published claim (``verdicts``), under a
banner after a quick run, then folds each study into a ``<details>``.
A warehouse scale's KPIs (tables, figures) cover the orders placed after its
warm-up (``runner.kpi_log``); its exported logs keep every order. From
``FIGURE_WORKERS_FROM`` swarm sizes on, worker processes draw the figures
while this process goes on with the statistics (``_Drawing``): the same files.
"""

from __future__ import annotations

import html
import json
import os
from collections.abc import Mapping, Sequence
from concurrent.futures import Future, ProcessPoolExecutor
from dataclasses import dataclass
from pathlib import Path
from types import TracebackType
from typing import Any, Final, Self

from swarmtag import __version__
from swarmtag._atomic import atomic_write_bytes
from swarmtag._inputs import check_path, is_regular_file
from swarmtag._outputs import OutputPlan
from swarmtag._pools import spawn_context, stop
from swarmtag.analysis import ConditionChoices, MetricsReport, choice_statistics, summarize
from swarmtag.analysis.choice_tables import choices_html, choices_latex, choices_markdown
from swarmtag.analysis.html import Section, write_html
from swarmtag.analysis.ranking import rank_conditions, ranking_html, ranking_markdown
from swarmtag.analysis.tables import (
    html_tables,
    latex_tables,
    markdown_tables,
    scalability_html,
    scalability_table,
)
from swarmtag.analysis.window import window_note
from swarmtag.errors import StudyError
from swarmtag.experiments.directions import DIRECTIONS, Direction
from swarmtag.experiments.runner import (
    QUICK_RESAMPLES,
    STORE_NAME,
    StudyResult,
    kpi_log,
    study_key,
)
from swarmtag.experiments.spec import Scale, Study
from swarmtag.experiments.store import ResultsStore, export_logs
from swarmtag.experiments.verdicts import judge_reports, quick_banner, verdict_section
from swarmtag.io import CarrierLog, EventTable

__all__ = ["REPORT_NAME", "RUN_RECORD", "StudyRecord", "write_report", "write_run_record"]

REPORT_NAME: Final = "report.html"
_SIGN_NOTE: Final = (
    "Relative changes are signed so that positive is better (a latency reduction is positive)."
)
_RANK_NOTE: Final = (
    "Ranked by PA, ties by throughput; Pareto-optimal: no other condition has both a PA and "
    "a throughput at least as large, one larger. Messages per delivery: the messages the "
    "robots sent (allocators that talk) over the deliveries."
)
FIGURE_WORKERS_FROM: Final = 4
"""Scales in a report from which worker processes draw its figures (three or four a scale):
below, the figures cost less than starting a worker (about a second: matplotlib's import)."""
RUN_RECORD: Final = "run.json"
"""Per-study file written after a run: wall time, quick or full, runs computed and reused."""


@dataclass(frozen=True, slots=True)
class StudyRecord:
    """What the last ``reproduce`` of a study did (kept in ``DIR/<study>/run.json``)."""

    wall_time_s: float
    quick: bool
    computed_runs: int
    reused_runs: int


def write_run_record(out_dir: str | os.PathLike[str], study: Study, record: StudyRecord) -> None:
    """Keep ``record`` next to the study's results."""
    data = {
        "wall_time_s": record.wall_time_s,
        "quick": record.quick,
        "computed_runs": record.computed_runs,
        "reused_runs": record.reused_runs,
    }
    path = Path(out_dir) / study.name / RUN_RECORD
    atomic_write_bytes(path, (json.dumps(data, indent=2) + "\n").encode())


def _read_record(out_dir: Path, study: Study) -> StudyRecord | None:
    path = out_dir / study.name / RUN_RECORD
    try:
        data: dict[str, Any] = json.loads(path.read_text(encoding="utf-8"))
        return StudyRecord(
            wall_time_s=float(data["wall_time_s"]),
            quick=bool(data["quick"]),
            computed_runs=int(data["computed_runs"]),
            reused_runs=int(data["reused_runs"]),
        )
    except FileNotFoundError:
        return None
    except (ValueError, KeyError, TypeError) as error:
        msg = f"{path}: not a study run record ({error})"
        raise StudyError(msg) from None


def _stored_runs(store: ResultsStore, study: Study) -> int:
    """Runs 0..n-1 stored for every condition and scale: the report covers exactly those."""
    counts = []
    for scale in study.scales:
        key = study_key(study, scale.key)
        for condition in study.conditions:
            stored = store.stored_runs(key, condition)
            n = 0
            while n in stored:
                n += 1
            counts.append(n)
    runs = min(counts)
    if runs == 0:
        msg = (
            f"study {study.name!r}: no complete runs in the store for this code version; "
            f"run it first (swarmtag study run {study.name})"
        )
        raise StudyError(msg)
    return runs


def _figure_workers(scales: int) -> int:
    """Worker processes to draw a report's figures in: none under ``FIGURE_WORKERS_FROM`` scales.

    Else one per core but this process's (at least one), at most one per scale.
    """
    if scales < FIGURE_WORKERS_FROM:
        return 0
    return max(1, min(scales, (os.cpu_count() or 1) - 1))


class _Drawing:
    """Draws each scale's figures: here, or in ``workers`` spawned processes meanwhile.

    With workers, this process goes on to the next scale's statistics and files
    while they draw (the same PNGs, byte for byte), then draws the scales no
    worker has started, last first; leaving the context waits for every figure
    and raises a worker's error, and an error or Ctrl-C here ends the workers.
    """

    def __init__(self, workers: int) -> None:
        self._pool = (
            ProcessPoolExecutor(max_workers=workers, mp_context=spawn_context())
            if workers > 0
            else None
        )
        self._pending: list[tuple[Future[list[Path]], MetricsReport, CarrierLog, Path]] = []

    def figures(self, report: MetricsReport, log: CarrierLog, folder: Path) -> list[Path]:
        """``write_figures(report, log, folder)``'s files, drawn or on their way."""
        from swarmtag.analysis.figures import (  # noqa: PLC0415 - matplotlib extra
            figure_files,
            write_figures,
        )

        if self._pool is None:
            return write_figures(report, log, folder)
        job = self._pool.submit(write_figures, report, log, folder)
        self._pending.append((job, report, log, folder))
        return figure_files(report, folder)

    def __enter__(self) -> Self:
        return self

    def __exit__(
        self,
        kind: type[BaseException] | None,
        error: BaseException | None,
        trace: TracebackType | None,
    ) -> None:
        if self._pool is None:
            return
        if kind is not None:
            stop(self._pool)
            return
        from swarmtag.analysis.figures import write_figures  # noqa: PLC0415 - matplotlib extra

        try:
            for job, report, log, folder in reversed(self._pending):
                if job.cancel():  # no worker took it yet: this process is free to draw it
                    write_figures(report, log, folder)
            for job, *_ in self._pending:
                if not job.cancelled():
                    job.result()
        except BaseException:
            stop(self._pool)
            raise
        self._pool.shutdown()


@dataclass(frozen=True, eq=False)
class _ScaleResult:
    """One scale's report, carrier logs and choice statistics (from the stored events)."""

    report: MetricsReport
    log: CarrierLog
    """The runs' carriers in the KPI window (``kpi_log``): what the tables and figures count."""
    stored: CarrierLog
    """Every stored carrier (a warehouse's warm-up too): what the exported log holds."""
    choices: tuple[ConditionChoices, ...]
    events: EventTable


def _scale_reports(
    store: ResultsStore,
    study: Study,
    runs: int,
    resamples: int,
    known: Mapping[str, MetricsReport],
) -> dict[str, _ScaleResult]:
    """Each scale's summary (``known`` ones reused), carrier logs and choice statistics.

    Each table is read from the store once: the export writes the same ones.
    """
    reports = {}
    for scale in study.scales:
        key = study_key(study, scale.key)
        stored = store.load_log(key, study.conditions, runs)
        log = kpi_log(stored, scale)
        report = known.get(scale.key) or summarize(
            log, baseline=study.baseline, n_resamples=resamples, seed=study.seed
        )
        events = store.load_events(key, study.conditions, runs)
        choices = choice_statistics(
            events,
            log=log,
            conditions=[c.condition for c in report.conditions],
            n_resamples=resamples,
            seed=study.seed,
        )
        reports[scale.key] = _ScaleResult(
            report=report, log=log, stored=stored, choices=choices, events=events
        )
    return reports


def _scale_fact(scale: Scale) -> str:
    """One scale in the facts: bodies, run length, floor (arena or warehouse), perception."""
    scenario = scale.scenario
    warehouse = scenario.warehouse
    if warehouse is None:
        bodies = f"{scenario.robots} robots / {scenario.carriers} carriers"
        floor = f"arena {scenario.area.size:g} m"
    else:
        bodies = f"{scenario.robots} robots"
        floor = (
            f"warehouse {warehouse.map} (an order every {warehouse.order_interval:g} s on "
            f"average, {warehouse.initial_orders} waiting at the start)"
        )
    return (
        f"{scale.key}: {bodies}, {scenario.run_ticks} ticks of {scenario.tick:g} s, "
        f"{floor}, {scenario.perception_summary()}"
    )


def _facts(study: Study, runs: int, resamples: int, record: StudyRecord | None) -> dict[str, str]:
    facts = {
        "description": study.description or "-",
        "conditions": ", ".join(study.conditions),
        "baseline": study.baseline,
        "runs per condition": str(runs),
        "urgency model": study.urgency,
        "swarm sizes": ", ".join(_scale_fact(s) for s in study.scales),
        "master seed": str(study.seed),
        "bootstrap": f"{resamples} resamples over runs",
        "code version": ", ".join(sorted({s.code_version for s in study.scales})),
    }
    windows = [
        f"{s.key}: {window_note(s.scenario.warehouse.warmup, 's')}"
        for s in study.scales
        if s.scenario.warehouse is not None
    ]
    if windows:
        facts["KPI window"] = "; ".join(windows) + " Choice statistics count whole runs."
    if record is not None:
        facts["wall time of the last run"] = (
            f"{record.wall_time_s:.1f} s ({'quick' if record.quick else 'full'}; "
            f"{record.computed_runs} runs computed, {record.reused_runs} reused)"
        )
    return facts


@dataclass(frozen=True, eq=False)
class _StudyReport:
    """One study in the report: its folded section, and what the verdicts and banner read."""

    section: Section
    reports: dict[str, MetricsReport]
    runs: int
    quick: bool


def _summary_line(study: Study, runs: int, quick: bool) -> str:
    """A folded study's line: its runs, conditions and swarm sizes."""
    line = f"{runs} runs per condition{' (quick)' if quick else ''}, "
    line += f"{len(study.conditions)} conditions"
    return line + (f", {len(study.scales)} swarm sizes" if len(study.scales) > 1 else "")


def _study_report(
    out_dir: Path,
    target_dir: Path,
    study: Study,
    *,
    store: Path,
    resamples: int | None,
    export_format: str,
    computed: Sequence[StudyResult],
    drawing: _Drawing,
) -> _StudyReport:
    """Read ``study``'s runs from ``store`` and its run record from ``out_dir``.

    Its logs, tables and figures (``drawing``'s) go to ``target_dir``.

    A summary in ``computed`` (``run_study``'s, this process) of the same
    study, runs and resamples is used as it is rather than bootstrapped again.
    """
    record = _read_record(out_dir, study)
    quick = record is not None and record.quick
    with ResultsStore(store, read_only=True) as stored:
        runs = _stored_runs(stored, study)
        if resamples is None:
            resamples = min(study.resamples, QUICK_RESAMPLES) if quick else study.resamples
        known = next(
            (
                result.reports
                for result in computed
                if (result.study, result.runs, result.resamples) == (study.name, runs, resamples)
            ),
            {},
        )
        reports = _scale_reports(stored, study, runs, resamples, known)
    scales = []
    for scale, result in reports.items():
        report, choices = result.report, result.choices
        folder = target_dir / study.name / scale
        (folder / "figures").mkdir(parents=True, exist_ok=True)
        export_logs(result.stored, result.events, folder, fmt=export_format)
        markdown = markdown_tables(report) + "\n" + choices_markdown(choices)
        atomic_write_bytes(folder / "tables.md", markdown.encode())
        latex = latex_tables(report) + "\n" + choices_latex(choices)
        atomic_write_bytes(folder / "tables.tex", latex.encode())
        scales.append(
            Section(
                title=f"swarm {scale}",
                tables_html=[html_tables(report), choices_html(choices)],
                figures=drawing.figures(report, result.log, folder / "figures"),
            )
        )
    summaries = {key: result.report for key, result in reports.items()}
    parts = []
    if len(reports) > 1:
        parts += scales
        parts.append(_scalability_section(target_dir, study, summaries))
    if study.ranking:
        parts.append(_ranking_section(target_dir, study, reports))
    # One swarm size: its tables and figures are the study's own, not a sub-section.
    own = scales[0] if len(reports) == 1 else Section(title=study.name)
    section = Section(
        title=study.name,
        summary=_summary_line(study, runs, quick),
        facts=_facts(study, runs, resamples, record),
        tables_html=own.tables_html,
        figures=own.figures,
        parts=parts,
    )
    return _StudyReport(section=section, reports=summaries, runs=runs, quick=quick)


def _ranking_section(out_dir: Path, study: Study, reports: Mapping[str, _ScaleResult]) -> Section:
    """The conditions ranked per scale (``ranking.md``) and the Pareto figure."""
    from swarmtag.analysis.figures import pareto_figure  # noqa: PLC0415 - matplotlib extra

    ranked = {key: rank_conditions(r.report, r.events) for key, r in reports.items()}
    units = {key: r.report.time_unit for key, r in reports.items()}
    markdown = "\n".join(
        ranking_markdown(rows, f"{study.name}, {key}", time_unit=units[key])
        for key, rows in ranked.items()
    )
    atomic_write_bytes(out_dir / study.name / "ranking.md", (markdown + "\n" + _RANK_NOTE).encode())
    figure = out_dir / study.name / "pareto.png"
    shared = set(units.values())
    pareto_figure(ranked, figure, time_unit=shared.pop() if len(shared) == 1 else None)
    return Section(
        title=f"{study.name}: the conditions ranked",
        paragraphs=[_RANK_NOTE],
        tables_html=[
            f"<h3>{html.escape(key)}</h3>" + ranking_html(rows, time_unit=units[key])
            for key, rows in ranked.items()
        ],
        figures=[figure],
    )


def _scalability_section(
    out_dir: Path, study: Study, reports: Mapping[str, MetricsReport]
) -> Section:
    others = [c for c in study.conditions if c != study.baseline]
    markdown = "\n".join(scalability_table(reports, condition=c) for c in others)
    latex = "\n".join(scalability_table(reports, condition=c, markdown=False) for c in others)
    atomic_write_bytes(out_dir / study.name / "scalability.md", markdown.encode())
    atomic_write_bytes(out_dir / study.name / "scalability.tex", latex.encode())
    return Section(
        title=f"{study.name}: relative change vs {study.baseline} per swarm size",
        paragraphs=[_SIGN_NOTE],
        tables_html=[scalability_html(reports, condition=c) for c in others],
    )


def write_report(
    out_dir: str | os.PathLike[str],
    studies: Sequence[Study],
    *,
    resamples: int | None = None,
    export_format: str = "csv",
    computed: Sequence[StudyResult] = (),
    store: str | os.PathLike[str] | None = None,
    sections: Sequence[Section] = (),
    directions: Sequence[Direction] = DIRECTIONS,
) -> Path:
    """Event logs, tables, figures and ``report.html`` of ``studies`` from ``out_dir``'s store.

    ``resamples`` defaults to each study's own (capped for quick runs); the
    event logs of every scale are exported as ``carriers.<fmt>`` and
    ``events.<fmt>`` (``export_format``: ``csv`` or ``parquet``). ``computed``:
    ``run_study`` results of this process whose summaries match are reused
    (the same numbers, computed once). ``store``: the results store file
    (default ``out_dir/results.duckdb``). The report opens with the verdict
    on each of ``directions`` in the studies it names (after a quick run,
    under a banner); ``sections`` follow it (the robustness over master
    seeds), then the studies, each folded.
    """
    folder = check_path(out_dir, what="DIR", error=StudyError)
    store_path = folder / STORE_NAME if store is None else Path(store)
    if not is_regular_file(store_path):
        where = folder if store is None else store_path.parent
        msg = f"{where}: no results store ({store_path.name}) here; run the studies first"
        raise StudyError(msg)
    plan = OutputPlan(error=StudyError)
    plan.folder("DIR", folder)
    workers = _figure_workers(sum(len(study.scales) for study in studies))
    with plan.writing() as stage:  # every file of the report, or none of them
        staged = stage.path(folder)
        with _Drawing(workers) as drawing:  # every figure drawn before the page embeds them
            done = [
                _study_report(
                    folder,
                    staged,
                    study,
                    store=store_path,
                    resamples=resamples,
                    export_format=export_format,
                    computed=computed,
                    drawing=drawing,
                )
                for study in studies
            ]
        claims = [
            claim
            for study, result in zip(studies, done, strict=True)
            for claim in judge_reports(study.name, study.seed, result.reports, directions)
        ]
        banner = ""
        if any(result.quick for result in done):
            banner = quick_banner(
                {study.name: result.runs for study, result in zip(studies, done, strict=True)},
                {study.name: study.runs for study in studies},
            )
        write_html(
            staged / REPORT_NAME,
            "swarmtag reproduction report",
            [verdict_section(claims), *sections, *(result.section for result in done)],
            facts={"swarmtag": __version__, "studies": ", ".join(s.name for s in studies)},
            banner=banner,
        )
    return folder / REPORT_NAME
