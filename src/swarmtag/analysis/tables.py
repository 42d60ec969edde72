"""Result tables as text: Markdown and LaTeX from a ``MetricsReport``, and the scalability table.

One number format everywhere (terminal, Markdown, LaTeX): four significant
digits, no exponent, ``n/a`` where a figure is undefined; bootstrap
p-values of 0 are shown as ``< 2/B``. Every latency table carries the
censoring-aware companions and the undelivered counts; a comparison whose
undelivered shares differ gets ``FLAG`` on its delivered-only latency rows
and one note line saying so. Pure: strings in, strings out.
"""

from __future__ import annotations

import html
import math
from collections.abc import Mapping, Sequence
from typing import Final

from swarmtag.analysis.compare import MIN_RUNS, Comparison
from swarmtag.analysis.kpis import CENSORED_METRICS, CORE_METRICS, OPTIONAL_METRICS
from swarmtag.analysis.summary import MetricsReport
from swarmtag.errors import StatisticsError

__all__ = [
    "DELIVERED_LATENCY_METRICS",
    "FLAG",
    "SCALABILITY_METRICS",
    "UNDERPOWERED",
    "censoring_notes",
    "flag_notes",
    "flagged",
    "format_interval",
    "format_number",
    "format_p_value",
    "html_table",
    "html_tables",
    "latex_tables",
    "markdown_table",
    "markdown_tables",
    "metric_cells",
    "metric_label",
    "pa_at_delivery_notes",
    "relative_change",
    "scalability_html",
    "scalability_notes",
    "scalability_table",
    "underpowered_notes",
    "unit_word",
]

_UNIT_WORDS: Final = {"s": "s", "tick": "ticks", None: "time units"}
_LABELS: Final = {
    "p95_latency": "P95 latency ({unit})",
    "mean_latency": "Mean latency ({unit})",
    "throughput": "Throughput (per 100 {unit})",
    "pa": "PA (5-50 %)",
    "deliveries_per_run": "Deliveries per run",
    "total_deliveries": "Total deliveries",
    "undelivered": "Undelivered carriers",
    "p95_latency_censored": "P95 latency, censored ({unit})",
    "mean_latency_censored": "Mean latency, censored ({unit})",
    "km_p95_latency": "KM P95 latency ({unit})",
    "pa_at_delivery": "PA at delivery (5-50 %)",
}
SCALABILITY_METRICS: Final = {
    "total_deliveries": 1,
    "undelivered": -1,
    "p95_latency": -1,
    "p95_latency_censored": -1,
    "km_p95_latency": -1,
    "pa": 1,
}
"""Metrics of the scalability table and the sign that makes a change "better" positive."""
DELIVERED_LATENCY_METRICS: Final = ("p95_latency", "mean_latency")
"""The latency rows biased when undelivered shares differ: they get ``FLAG``."""
FLAG: Final = "\N{DAGGER}"
"""Marks a delivered-only latency row whose two conditions left different shares undelivered."""
UNDERPOWERED: Final = "\N{DOUBLE DAGGER}"
"""Marks a bootstrap CI and p-value of an underpowered comparison (``Comparison.underpowered``)."""
_COUNTS: Final = ("total_deliveries", "undelivered")


def unit_word(time_unit: str | None) -> str:
    """``ticks``, ``s`` or ``time units`` for an unknown unit."""
    return _UNIT_WORDS.get(time_unit, str(time_unit))


def metric_label(metric: str, time_unit: str | None) -> str:
    """A metric's name for tables, with its unit: ``P95 latency (ticks)``."""
    return _LABELS[metric].format(unit=unit_word(time_unit))


def format_number(value: float | None) -> str:
    """Four significant digits without an exponent; ``n/a`` where undefined.

    >>> format_number(3271.5), format_number(0.34752), format_number(700), format_number(None)
    ('3272', '0.3475', '700', 'n/a')
    """
    if value is None or math.isnan(value):
        return "n/a"
    if isinstance(value, int):
        return str(value)
    if value == 0:
        return "0"
    magnitude = math.floor(math.log10(abs(value)))
    return f"{value:.{min(4, max(0, 3 - magnitude))}f}"


def format_interval(value: float | None, low: float | None, high: float | None) -> str:
    """``value [low, high]``, or just the value when the interval is undefined."""
    interval = (
        "" if low is None or high is None else f" [{format_number(low)}, {format_number(high)}]"
    )
    return f"{format_number(value)}{interval}"


def format_p_value(p: float | None, resamples: int) -> str:
    """Three significant digits; a bootstrap p of 0 is below the resolution 2/B.

    >>> format_p_value(0.0, 10_000), format_p_value(0.03456, 10_000)
    ('< 0.0002', '0.0346')
    """
    if p is None:
        return "n/a"
    if p == 0:
        return f"< {2 / resamples:.2g}"
    return f"{p:.3g}"


def flagged(comparison: Comparison) -> bool:
    """Whether a comparison's row gets ``FLAG``: delivered-only latency, undelivered differs."""
    return comparison.undelivered_differs and comparison.metric in DELIVERED_LATENCY_METRICS


def metric_cells(report: MetricsReport, metric: str) -> list[str]:
    """One cell per condition: ``value [low, high]``, or ``-`` where it has no such metric."""
    cells = []
    for c in report.conditions:
        if metric not in c.metrics:
            cells.append("-")  # PA at delivery of a condition whose log lacks urgency_end
            continue
        estimate = c.estimate(metric)
        interval = estimate.confidence_interval
        cells.append(format_interval(estimate.value, interval.low, interval.high))
    return cells


def _value_row(report: MetricsReport, metric: str) -> list[str]:
    return [metric_label(metric, report.time_unit), *metric_cells(report, metric)]


def _rows(report: MetricsReport) -> tuple[list[str], list[list[str]], list[str], list[list[str]]]:
    """Header and cells of the value table and of the difference table."""
    names = [c.condition for c in report.conditions]
    value_rows = [_value_row(report, metric) for metric in CORE_METRICS]
    value_rows.append(
        [metric_label("total_deliveries", report.time_unit)]
        + [str(c.kpis.total_deliveries) for c in report.conditions]
    )
    value_rows.append(
        ["Undelivered carriers"] + [str(c.kpis.undelivered) for c in report.conditions]
    )
    value_rows += [_value_row(report, metric) for metric in CENSORED_METRICS]
    value_rows += [
        _value_row(report, metric)
        for metric in OPTIONAL_METRICS
        if any(metric in c.metrics for c in report.conditions)
    ]
    diff_header = [
        "Condition",
        "Metric",
        "Difference [95 % CI]",
        "p (bootstrap)",
        "p (Mann-Whitney)",
    ]
    diff_rows = [
        [
            k.condition,
            metric_label(k.metric, report.time_unit) + (f" {FLAG}" if flagged(k) else ""),
            format_interval(k.diff, k.confidence_interval.low, k.confidence_interval.high)
            + (f" {UNDERPOWERED}" if k.underpowered else ""),
            format_p_value(k.p_bootstrap, report.n_resamples)
            + (f" {UNDERPOWERED}" if k.underpowered else ""),
            format_p_value(k.p_mannwhitney, report.n_resamples),
        ]
        for k in report.comparisons
    ]
    return ["Metric", *names], value_rows, diff_header, diff_rows


def markdown_table(header: Sequence[str], rows: Sequence[Sequence[str]]) -> str:
    """A Markdown table of text cells (not escaped: numbers and names)."""
    lines = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    lines += ["| " + " | ".join(row) + " |" for row in rows]
    return "\n".join(lines)


def censoring_notes(report: MetricsReport) -> list[str]:
    """What the censored rows mean, where run ends came from, and what PA at delivery is."""
    notes = [
        (
            "Censored rows count each undelivered carrier at run end - order time, its least "
            "possible latency: they are lower bounds. KM P95 is the 95th percentile of the "
            "Kaplan-Meier latency distribution with undelivered carriers right-censored there "
            "(n/a where the KM curve stays below 0.95)."
        )
    ]
    without = [c for c in report.conditions if c.kpis.runs_without_run_end]
    if without:
        counts = ", ".join(f"{c.condition} {c.kpis.runs_without_run_end}" for c in without)
        notes.append(
            f"Runs without run_end in the log ({counts}) end at their latest pickup or "
            "delivery: a weaker lower bound."
        )
    return notes + pa_at_delivery_notes(report)


def pa_at_delivery_notes(report: MetricsReport) -> list[str]:
    """What PA at delivery is, where the report has it (one line), else nothing."""
    if not any("pa_at_delivery" in c.metrics for c in report.conditions):
        return []
    return [
        (
            "PA at delivery ranks carriers by their urgency when delivered (undelivered: at "
            "run end), a comparison aid; PA itself ranks by urgency at run start."
        )
    ]


def flag_notes(report: MetricsReport) -> list[str]:
    """One line per condition flagged against the baseline (see ``flagged``)."""
    notes = []
    seen = set()
    for k in report.comparisons:
        if k.undelivered_differs and k.condition not in seen:
            seen.add(k.condition)
            notes.append(
                f"{FLAG} {k.condition}: undelivered differs from {k.baseline} "
                f"({k.undelivered[0]} vs {k.undelivered[1]}): delivered-only latency is biased; "
                "compare the censored rows."
            )
    return notes


def underpowered_notes(report: MetricsReport) -> list[str]:
    """One line when any comparison is underpowered: the rule, and the test to read instead."""
    weak = [k for k in report.comparisons if k.underpowered]
    if not weak:
        return []
    fewest = min(min(k.runs) for k in weak)
    floor = min(k.smallest_p for k in weak)
    note = (
        f"{UNDERPOWERED} underpowered: {fewest} run(s) per condition, fewer than {MIN_RUNS}. "
        "The bootstrap over so few runs gives CIs too narrow and p-values that reach 0; "
        f"read Mann-Whitney, whose smallest possible p here is {floor:.3g}."
    )
    return [note]


def _note(report: MetricsReport) -> str:
    undelivered = ", ".join(f"{c.condition} {c.kpis.undelivered}" for c in report.conditions)
    return (
        f"Latency covers delivered carriers only (undelivered: {undelivered}). "
        f"95 % bootstrap CIs over whole runs, {report.n_resamples} resamples, seed {report.seed}; "
        f"differences are condition - {report.baseline}."
    )


def _notes(report: MetricsReport) -> list[str]:
    return [
        _note(report),
        *censoring_notes(report),
        *flag_notes(report),
        *underpowered_notes(report),
    ]


def markdown_tables(report: MetricsReport) -> str:
    """The value table and the difference table of a report, as Markdown, then the notes."""
    header, values, diff_header, diffs = _rows(report)
    parts = [markdown_table(header, values)]
    if diffs:
        parts.append(markdown_table(diff_header, diffs))
    parts.append("\n".join(_notes(report)))
    return "\n\n".join(parts) + "\n"


_LATEX_SPECIAL: Final = {
    "&": r"\&",
    "%": r"\%",
    "_": r"\_",
    "#": r"\#",
    "<": r"$<$",
    FLAG: r"\textsuperscript{\dag}",
    UNDERPOWERED: r"\textsuperscript{\ddag}",
}


def _latex_escape(text: str) -> str:
    return "".join(_LATEX_SPECIAL.get(char, char) for char in text)


def _latex(header: Sequence[str], rows: Sequence[Sequence[str]]) -> str:
    spec = "l" + "r" * (len(header) - 1)
    lines = [
        rf"\begin{{tabular}}{{{spec}}}",
        r"\toprule",
        " & ".join(_latex_escape(h) for h in header) + r" \\",
        r"\midrule",
    ]
    lines += [" & ".join(_latex_escape(cell) for cell in row) + r" \\" for row in rows]
    lines += [r"\bottomrule", r"\end{tabular}"]
    return "\n".join(lines)


def latex_tables(report: MetricsReport) -> str:
    """The same tables as LaTeX ``tabular`` environments (booktabs rules)."""
    header, values, diff_header, diffs = _rows(report)
    parts = [_latex(header, values)]
    if diffs:
        parts.append(_latex(diff_header, diffs))
    parts.append("\n".join("% " + note for note in _notes(report)))
    return "\n\n".join(parts) + "\n"


def html_table(header: Sequence[str], rows: Sequence[Sequence[str]]) -> str:
    """An HTML ``<table>`` of text cells, each escaped."""
    head = "".join(f"<th>{html.escape(h)}</th>" for h in header)
    body = "".join(
        "<tr>" + "".join(f"<td>{html.escape(cell)}</td>" for cell in row) + "</tr>" for row in rows
    )
    return f"<table><thead><tr>{head}</tr></thead><tbody>{body}</tbody></table>"


def html_tables(report: MetricsReport) -> str:
    """The same tables as HTML ``<table>`` elements, with the note as a paragraph."""
    header, values, diff_header, diffs = _rows(report)
    parts = [html_table(header, values)]
    if diffs:
        parts.append(html_table(diff_header, diffs))
    parts += [f'<p class="note">{html.escape(note)}</p>' for note in _notes(report)]
    return "\n".join(parts)


def relative_change(metric: str, baseline: float | None, value: float | None) -> float | None:
    """Relative change vs the baseline, signed so that positive is better.

    >>> relative_change("p95_latency", 200.0, 150.0)  # 25 % lower latency: better
    0.25
    >>> relative_change("pa", 0.5, 0.625)
    0.25
    """
    if metric not in SCALABILITY_METRICS:
        raise StatisticsError(
            f"no sign for metric {metric!r}; expected one of {list(SCALABILITY_METRICS)}"
        )
    if baseline is None or value is None or baseline == 0:
        return None
    return SCALABILITY_METRICS[metric] * (value - baseline) / baseline


_SCALABILITY_HEADER: Final = ("Swarm", "Metric", "Baseline", "Condition", "Change (+ is better)")


def _differs(report: MetricsReport, condition: str) -> Comparison | None:
    """A comparison of ``condition`` with the baseline, if their undelivered shares differ."""
    return next(
        (k for k in report.comparisons if k.condition == condition and k.undelivered_differs),
        None,
    )


def _scalability_rows(reports: Mapping[str, MetricsReport], *, condition: str) -> list[list[str]]:
    rows = []
    for label, report in reports.items():
        base = report.condition(report.baseline).kpis
        other = report.condition(condition).kpis
        mark = f" {FLAG}" if _differs(report, condition) else ""
        for metric in SCALABILITY_METRICS:
            b = getattr(base, metric) if metric in _COUNTS else base.value(metric)
            v = getattr(other, metric) if metric in _COUNTS else other.value(metric)
            change = relative_change(metric, b, v)
            rows.append(
                [
                    label,
                    metric_label(metric, report.time_unit)
                    + (mark if metric in DELIVERED_LATENCY_METRICS else ""),
                    format_number(b),
                    format_number(v),
                    "n/a" if change is None else f"{100 * change:+.1f} %",
                ]
            )
    return rows


def scalability_table(
    reports: Mapping[str, MetricsReport], *, condition: str, markdown: bool = True
) -> str:
    """Per swarm size: baseline and ``condition`` values and the signed relative change.

    ``reports`` maps a size label (``"5/10"``) to that size's report. The
    notes (``scalability_notes``) follow the table.
    """
    rows = _scalability_rows(reports, condition=condition)
    header = _SCALABILITY_HEADER
    notes = scalability_notes(reports, condition=condition)
    if markdown:
        return "\n\n".join([markdown_table(header, rows), *notes]) + "\n"
    return "\n".join([_latex(header, rows), *("% " + note for note in notes)]) + "\n"


def scalability_notes(reports: Mapping[str, MetricsReport], *, condition: str) -> list[str]:
    """One line per swarm size whose undelivered counts differ (``FLAG`` rows of the table)."""
    notes = []
    for label, report in reports.items():
        k = _differs(report, condition)
        if k is not None:
            notes.append(
                f"{FLAG} {label}: undelivered differs ({k.undelivered[0]} vs "
                f"{k.undelivered[1]}): delivered-only latency is biased; compare the censored rows."
            )
    return notes


def scalability_html(reports: Mapping[str, MetricsReport], *, condition: str) -> str:
    """The scalability table as an HTML ``<table>``, then its notes."""
    table = html_table(_SCALABILITY_HEADER, _scalability_rows(reports, condition=condition))
    notes = scalability_notes(reports, condition=condition)
    return "\n".join([table, *(f'<p class="note">{html.escape(n)}</p>' for n in notes)])
