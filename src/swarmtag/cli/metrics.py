"""``swarmtag metrics EVENTS``: KPIs with bootstrap CIs, compared with a baseline (SPEC §8.2)."""

from __future__ import annotations

import json
import math
from pathlib import Path

import click
from rich.console import Console, JustifyMethod
from rich.table import Table

from swarmtag.analysis import METRICS, MetricsReport, summarize
from swarmtag.cli._console import make_console
from swarmtag.cli._options import baseline_option, resamples_option
from swarmtag.io import read_event_log

__all__ = ["metrics"]

_UNIT_WORDS = {"s": "s", "tick": "ticks", None: "time units"}
_LABELS = {
    "p95_latency": "P95 latency ({unit})",
    "mean_latency": "Mean latency ({unit})",
    "throughput": "Throughput (per 100 {unit})",
    "pa": "PA (5-50 %)",
    "deliveries_per_run": "Deliveries per run",
}


def _number(value: float | None) -> str:
    """Four significant digits without an exponent; ``n/a`` where undefined."""
    if value is None or math.isnan(value):
        return "n/a"
    if value == 0:
        return "0"
    magnitude = math.floor(math.log10(abs(value)))
    return f"{value:.{min(4, max(0, 3 - magnitude))}f}"


def _with_interval(value: float | None, low: float | None, high: float | None) -> str:
    interval = "" if low is None or high is None else f" [{_number(low)}, {_number(high)}]"
    return f"{_number(value)}{interval}"


def _p_value(p: float | None, resamples: int) -> str:
    if p is None:
        return "n/a"
    if p == 0:
        return f"< {2 / resamples:.2g}"
    return f"{p:.3g}"


def _label(metric: str, unit: str) -> str:
    return _LABELS[metric].format(unit=unit)


def _time_note(time_unit: str | None) -> str:
    if time_unit == "s":
        return "Times are in seconds (time_unit s)."
    if time_unit == "tick":
        return "Times are in simulator ticks (time_unit tick)."
    return (
        "The log does not state its time unit (no time_unit column): "
        "ticks for simulated runs, seconds for physical trials."
    )


def render_report(report: MetricsReport, console: Console) -> None:
    unit = _UNIT_WORDS.get(report.time_unit, "time units")
    level = f"{report.confidence_level * 100:g} %"
    kpis = Table(title=f"Metrics by condition: value [{level} CI]", title_justify="left")
    kpis.add_column("Metric")
    for statistics in report.conditions:
        kpis.add_column(statistics.condition, justify="right")
    kpis.add_row("Runs", *(str(s.kpis.runs) for s in report.conditions))
    for metric in METRICS:
        cells = []
        for statistics in report.conditions:
            estimate = statistics.estimate(metric)
            interval = estimate.confidence_interval
            cells.append(_with_interval(estimate.value, interval.low, interval.high))
        kpis.add_row(_label(metric, unit), *cells)
    kpis.add_row("Total deliveries", *(str(s.kpis.total_deliveries) for s in report.conditions))
    kpis.add_row("Undelivered carriers", *(str(s.kpis.undelivered) for s in report.conditions))
    console.print(kpis)

    if report.comparisons:
        diffs = Table(
            title=f"Differences from the baseline {report.baseline} (condition - baseline)",
            title_justify="left",
        )
        columns: tuple[tuple[str, JustifyMethod], ...] = (
            ("Condition", "left"),
            ("Metric", "left"),
            (f"Difference [{level} CI]", "right"),
            ("p (bootstrap)", "right"),
            ("p (Mann-Whitney)", "right"),
        )
        for name, justify in columns:
            diffs.add_column(name, justify=justify)
        for comparison in report.comparisons:
            interval = comparison.confidence_interval
            diffs.add_row(
                comparison.condition,
                _label(comparison.metric, unit),
                _with_interval(comparison.diff, interval.low, interval.high),
                _p_value(comparison.p_bootstrap, report.n_resamples),
                _p_value(comparison.p_mannwhitney, report.n_resamples),
            )
        console.print(diffs)
    else:
        console.print(f"Only one condition ({report.baseline}): nothing to compare.")

    undelivered = ", ".join(f"{s.condition} {s.kpis.undelivered}" for s in report.conditions)
    console.print(
        "Latency covers delivered carriers only (undelivered carriers have none); "
        f"undelivered: {undelivered}.",
        highlight=False,
    )
    console.print(_time_note(report.time_unit), highlight=False)
    for statistics in report.conditions:
        for metric in METRICS:
            estimate = statistics.estimate(metric)
            missing = estimate.n_undefined
            if missing and estimate.value is not None:  # undefined outright shows as n/a
                console.print(
                    f"{_label(metric, unit)} of {statistics.condition} was undefined in "
                    f"{missing} of {report.n_resamples} resamples (left out of its CI).",
                    highlight=False,
                )
    console.print(
        f"CIs: bootstrap over whole runs, {report.n_resamples} resamples, seed {report.seed}; "
        "p (bootstrap) = min(1, 2 min(#diff*<=0, #diff*>=0) / B); "
        "Mann-Whitney U two-sided on per-run values.",
        highlight=False,
    )


@click.command("metrics")
@click.argument("events", metavar="EVENTS", type=click.Path(path_type=Path))
@baseline_option
@resamples_option
@click.option(
    "--seed",
    type=click.IntRange(min=0),
    default=0,
    show_default=True,
    metavar="S",
    help="Master seed of the bootstrap (each condition's stream is keyed by its name).",
)
@click.option(
    "--json", "as_json", is_flag=True, help="Print one JSON object (SPEC §8.2) instead of tables."
)
def metrics(
    events: Path, *, baseline: str | None, resamples: int, seed: int, as_json: bool
) -> None:
    """KPIs of an event log EVENTS (.csv or .parquet) with 95 % bootstrap CIs over runs.

    For every condition: P95 and mean latency (delivered carriers, pooled over
    runs), throughput, priority alignment PA (5-50 %), deliveries per run, total
    deliveries and undelivered carriers. Each other condition is compared with
    the baseline: difference with CI, bootstrap p-value and Mann-Whitney U.
    """
    report = summarize(read_event_log(events), baseline=baseline, n_resamples=resamples, seed=seed)
    if as_json:
        click.echo(json.dumps(report.to_json(), allow_nan=False))
        return
    render_report(report, make_console())
