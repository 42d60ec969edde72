"""``swarmtag metrics EVENTS``: KPIs with bootstrap CIs, compared with a baseline."""

from __future__ import annotations

import json
import sys
import tempfile
from collections.abc import Sequence
from contextlib import nullcontext
from pathlib import Path
from typing import overload

import click
from rich.console import Console

from swarmtag import __version__
from swarmtag._atomic import atomic_write_bytes
from swarmtag._checks import MAX_SEED, check_number
from swarmtag._outputs import OutputPlan, Stage
from swarmtag.analysis import MetricsReport, summarize, trim_warmup
from swarmtag.analysis.choice_tables import choices_html, choices_latex, choices_markdown
from swarmtag.analysis.choices import ConditionChoices, choice_statistics
from swarmtag.analysis.html import Section, write_html
from swarmtag.analysis.tables import html_tables, latex_tables, markdown_tables, unit_word
from swarmtag.analysis.window import window_note
from swarmtag.cli._console import make_console
from swarmtag.cli._options import baseline_option, check_bootstrap_memory, resamples_option
from swarmtag.cli._report import render_choices, render_report
from swarmtag.cli._testing import tests_beside
from swarmtag.errors import StatisticsError
from swarmtag.io import CarrierLog, EventTable, read_event_log, read_event_table

__all__ = ["metrics", "render_choices", "render_report", "summarize_with_choices"]


@overload
def summarize_with_choices(
    log: CarrierLog, table: EventTable, *, baseline: str | None, resamples: int, seed: int
) -> tuple[MetricsReport, tuple[ConditionChoices, ...]]: ...
@overload
def summarize_with_choices(
    log: CarrierLog, table: EventTable | None, *, baseline: str | None, resamples: int, seed: int
) -> tuple[MetricsReport, tuple[ConditionChoices, ...] | None]: ...
def summarize_with_choices(
    log: CarrierLog,
    table: EventTable | None,
    *,
    baseline: str | None,
    resamples: int,
    seed: int,
) -> tuple[MetricsReport, tuple[ConditionChoices, ...] | None]:
    """The KPI report of ``log`` and, given its event table, the choice statistics too."""
    report = summarize(log, baseline=baseline, n_resamples=resamples, seed=seed)
    if table is None:
        return report, None
    choices = choice_statistics(
        table,
        log=log,
        conditions=[c.condition for c in report.conditions],
        n_resamples=resamples,
        seed=seed,
    )
    return report, choices


def _write_html(
    path: Path,
    events: Path,
    report: MetricsReport,
    log: CarrierLog,
    choices: Sequence[ConditionChoices] | None,
    *,
    warmup: float,
) -> None:
    """One-section HTML report of an event log: tables and embedded figures."""
    from swarmtag.analysis.figures import write_figures  # noqa: PLC0415 - matplotlib extra

    # The figures are made beside the staged page, on its device, and go with its staging.
    with tempfile.TemporaryDirectory(dir=path.parent, prefix=".figures-") as folder:
        section = Section(
            title=f"Event log {events.name}",
            facts={
                "conditions": ", ".join(c.condition for c in report.conditions),
                "runs": ", ".join(f"{c.condition} {c.kpis.runs}" for c in report.conditions),
                "baseline": report.baseline,
                "time unit": unit_word(report.time_unit),
                "bootstrap": f"{report.n_resamples} resamples over runs, seed {report.seed}",
            }
            | ({"KPI window": window_note(warmup, unit_word(report.time_unit))} if warmup else {}),
            tables_html=[html_tables(report)] + ([choices_html(choices)] if choices else []),
            figures=write_figures(report, log, folder),
        )
        write_html(
            path,
            f"swarmtag metrics: {events.name}",
            [section],
            facts={"swarmtag": __version__, "source": str(events)},
        )


def _write_outputs(
    stage: Stage,
    report: MetricsReport,
    log: CarrierLog,
    choices: Sequence[ConditionChoices] | None,
    *,
    events: Path,
    markdown: Path | None,
    latex: Path | None,
    html_out: Path | None,
    figures: Path | None,
    warmup: float,
) -> list[str]:
    """Write the planned outputs into ``stage``; what was written, for the closing lines."""
    written = []
    if markdown is not None:
        text = markdown_tables(report) + ("\n" + choices_markdown(choices) if choices else "")
        atomic_write_bytes(stage.path(markdown), text.encode())
        written.append(f"Markdown tables: {markdown}")
    if latex is not None:
        text = latex_tables(report) + ("\n" + choices_latex(choices) if choices else "")
        atomic_write_bytes(stage.path(latex), text.encode())
        written.append(f"LaTeX tables: {latex}")
    if figures is not None:
        from swarmtag.analysis.figures import write_figures  # noqa: PLC0415 - matplotlib

        drawn = write_figures(report, log, stage.path(figures))
        written += [f"figure: {figures / path.name}" for path in drawn]
    if html_out is not None:
        _write_html(stage.path(html_out), events, report, log, choices, warmup=warmup)
        written.append(f"HTML report: {html_out}")
    return written


@click.command("metrics")
@click.argument("events", metavar="EVENTS", type=click.Path(path_type=Path))
@baseline_option
@resamples_option
@click.option(
    "--seed",
    type=click.IntRange(0, MAX_SEED),
    default=0,
    show_default=True,
    metavar="S",
    help="Master seed of the bootstrap (each condition's stream is keyed by its name).",
)
@click.option(
    "--warmup",
    type=float,
    default=0.0,
    show_default=True,
    metavar="T",
    help="Leave out the orders placed before T (the log's time unit): the KPIs of continuous "
    "operation, e.g. a warehouse run, over the orders placed after its warm-up.",
)
@click.option(
    "--json",
    "as_json",
    is_flag=True,
    help="Print one JSON object instead of tables (docs/metrics.md).",
)
@click.option(
    "--event-table",
    type=click.Path(path_type=Path),
    metavar="FILE",
    help="The long-format event table of the same runs (.csv or .parquet): adds the choice "
    "statistics (selections, candidates, double pursuits, timeouts, abandons), under --json "
    'as the key "choices".',
)
@click.option(
    "--markdown", type=click.Path(path_type=Path), help="Also write the tables as Markdown."
)
@click.option("--latex", type=click.Path(path_type=Path), help="Also write the tables as LaTeX.")
@click.option(
    "--html",
    "html_out",
    type=click.Path(path_type=Path),
    help="Also write one self-contained HTML report: the tables and every figure.",
)
@click.option(
    "--figures",
    type=click.Path(file_okay=False, path_type=Path),
    help="Also draw the PA and latency curves with bands, latency per urgency level and, "
    "for a one-policy sweep, the parameter sweep, as PNGs in this folder.",
)
def metrics(
    events: Path,
    *,
    baseline: str | None,
    resamples: int,
    seed: int,
    warmup: float,
    as_json: bool,
    event_table: Path | None,
    markdown: Path | None,
    latex: Path | None,
    html_out: Path | None,
    figures: Path | None,
) -> None:
    """KPIs of an event log EVENTS (.csv or .parquet) with 95 % bootstrap CIs over runs.

    For every condition: P95 and mean latency (delivered carriers, pooled over
    runs), throughput, priority alignment PA (5-50 %), deliveries per run, total
    deliveries and undelivered carriers, and the censoring-aware latencies
    (undelivered carriers counted at run end - order time: lower bounds; the
    Kaplan-Meier P95). Each other condition is compared with the baseline:
    difference with CI, bootstrap p-value and Mann-Whitney U. With --warmup T
    every figure covers the orders placed at or after T, followed to the run's end.
    """
    start = check_number("--warmup", warmup, low=0.0, error=StatisticsError)  # nan, inf pass click
    plan = OutputPlan()
    plan.input("EVENTS", events)
    if event_table is not None:
        plan.input("--event-table", event_table)
    for option, path, suffixes in (
        ("--markdown", markdown, (".md", ".markdown")),
        ("--latex", latex, (".tex",)),
        ("--html", html_out, (".html", ".htm")),
    ):
        if path is not None:
            plan.file(option, path, suffixes=suffixes)
    if figures is not None:
        plan.folder("--figures", figures)
    log = trim_warmup(read_event_log(events), start)
    table = read_event_table(event_table) if event_table is not None else None
    check_bootstrap_memory(resamples, len(log), len(log.conditions))
    status = Console(stderr=True).status(
        f"bootstrapping {resamples} resamples of {len(log.conditions)} condition(s)"
    )
    # forked before the statistics load their compiled loops: scipy.stats is imported beside
    with (
        tests_beside(comparing=len(log.conditions) > 1),
        plan.writing() as stage,
        status if sys.stderr.isatty() else nullcontext(),
    ):
        report, choices = summarize_with_choices(
            log, table, baseline=baseline, resamples=resamples, seed=seed
        )
        written = _write_outputs(
            stage,
            report,
            log,
            choices,
            events=events,
            markdown=markdown,
            latex=latex,
            html_out=html_out,
            figures=figures,
            warmup=start,
        )
    if as_json:
        document = report.to_json()
        if choices is not None:
            document["choices"] = [c.to_json() for c in choices]
        click.echo(json.dumps(document, allow_nan=False))
        for line in written:
            click.echo(f"wrote {line}", err=True)
        return
    console = make_console()
    render_report(report, console)
    if start:
        console.print(window_note(start, unit_word(report.time_unit)), highlight=False)
    if choices is not None:
        render_choices(choices, console)
    for line in written:
        console.print(f"wrote {line}", highlight=False)
