"""Result tables as text: Markdown and LaTeX from a ``MetricsReport``, and the scalability table.

One number format everywhere (terminal, Markdown, LaTeX): four significant
digits, no exponent, ``n/a`` where a figure is undefined; bootstrap
p-values of 0 are shown as ``< 2/B``. Pure: strings in, strings out.
"""

from __future__ import annotations

import html
import math
from collections.abc import Mapping, Sequence
from typing import Final

from swarmtag.analysis.kpis import METRICS
from swarmtag.analysis.summary import MetricsReport
from swarmtag.errors import StatisticsError

__all__ = [
    "SCALABILITY_METRICS",
    "format_interval",
    "format_number",
    "format_p_value",
    "html_tables",
    "latex_tables",
    "markdown_tables",
    "metric_label",
    "relative_change",
    "scalability_html",
    "scalability_table",
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
}
SCALABILITY_METRICS: Final = {"total_deliveries": 1, "p95_latency": -1, "pa": 1}
"""Metrics of the scalability table and the sign that makes a change "better" positive."""


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


def _rows(report: MetricsReport) -> tuple[list[str], list[list[str]], list[str], list[list[str]]]:
    """Header and cells of the value table and of the difference table."""
    names = [c.condition for c in report.conditions]
    value_rows = [
        [metric_label(metric, report.time_unit)]
        + [
            format_interval(
                c.estimate(metric).value,
                c.estimate(metric).confidence_interval.low,
                c.estimate(metric).confidence_interval.high,
            )
            for c in report.conditions
        ]
        for metric in METRICS
    ]
    value_rows.append(
        [metric_label("total_deliveries", report.time_unit)]
        + [str(c.kpis.total_deliveries) for c in report.conditions]
    )
    value_rows.append(
        ["Undelivered carriers"] + [str(c.kpis.undelivered) for c in report.conditions]
    )
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
            metric_label(k.metric, report.time_unit),
            format_interval(k.diff, k.confidence_interval.low, k.confidence_interval.high),
            format_p_value(k.p_bootstrap, report.n_resamples),
            format_p_value(k.p_mannwhitney, report.n_resamples),
        ]
        for k in report.comparisons
    ]
    return ["Metric", *names], value_rows, diff_header, diff_rows


def _markdown(header: Sequence[str], rows: Sequence[Sequence[str]]) -> str:
    lines = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    lines += ["| " + " | ".join(row) + " |" for row in rows]
    return "\n".join(lines)


def _note(report: MetricsReport) -> str:
    undelivered = ", ".join(f"{c.condition} {c.kpis.undelivered}" for c in report.conditions)
    return (
        f"Latency covers delivered carriers only (undelivered: {undelivered}). "
        f"95 % bootstrap CIs over whole runs, {report.n_resamples} resamples, seed {report.seed}; "
        f"differences are condition - {report.baseline}."
    )


def markdown_tables(report: MetricsReport) -> str:
    """The value table and the difference table of a report, as Markdown."""
    header, values, diff_header, diffs = _rows(report)
    parts = [_markdown(header, values)]
    if diffs:
        parts.append(_markdown(diff_header, diffs))
    parts.append(_note(report))
    return "\n\n".join(parts) + "\n"


_LATEX_SPECIAL: Final = {"&": r"\&", "%": r"\%", "_": r"\_", "#": r"\#", "<": r"$<$"}


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
    parts.append("% " + _note(report))
    return "\n\n".join(parts) + "\n"


def _html(header: Sequence[str], rows: Sequence[Sequence[str]]) -> str:
    head = "".join(f"<th>{html.escape(h)}</th>" for h in header)
    body = "".join(
        "<tr>" + "".join(f"<td>{html.escape(cell)}</td>" for cell in row) + "</tr>" for row in rows
    )
    return f"<table><thead><tr>{head}</tr></thead><tbody>{body}</tbody></table>"


def html_tables(report: MetricsReport) -> str:
    """The same tables as HTML ``<table>`` elements, with the note as a paragraph."""
    header, values, diff_header, diffs = _rows(report)
    parts = [_html(header, values)]
    if diffs:
        parts.append(_html(diff_header, diffs))
    parts.append(f'<p class="note">{html.escape(_note(report))}</p>')
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


def _scalability_rows(reports: Mapping[str, MetricsReport], *, condition: str) -> list[list[str]]:
    rows = []
    for label, report in reports.items():
        base = report.condition(report.baseline).kpis
        other = report.condition(condition).kpis
        for metric in SCALABILITY_METRICS:
            b = base.total_deliveries if metric == "total_deliveries" else base.value(metric)
            v = other.total_deliveries if metric == "total_deliveries" else other.value(metric)
            change = relative_change(metric, b, v)
            rows.append(
                [
                    label,
                    metric_label(metric, report.time_unit),
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

    ``reports`` maps a size label (``"5/10"``) to that size's report.
    """
    rows = _scalability_rows(reports, condition=condition)
    header = _SCALABILITY_HEADER
    return (_markdown(header, rows) if markdown else _latex(header, rows)) + "\n"


def scalability_html(reports: Mapping[str, MetricsReport], *, condition: str) -> str:
    """The scalability table as an HTML ``<table>``."""
    return _html(_SCALABILITY_HEADER, _scalability_rows(reports, condition=condition))
