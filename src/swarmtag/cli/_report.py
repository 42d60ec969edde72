"""A metrics report on the terminal: headlines, then tables that fit the console's width.

One place for ``swarmtag simulate``, ``swarmtag metrics`` and ``swarmtag
demo``. What is printed, in order: one headline per treatment
(``analysis.headline``), the value table, the differences table, the notes,
and (given an event table) the choice statistics.

Tables never cut a condition's name or a number: a cell ``0.41 [0.38,
0.44]`` is never wrapped (``no_wrap``), and the layouts are tried in turn
at the console's width (``_needed`` computes what each takes) until one
shows every cell whole:

1. one column per condition, headed by its name, else by a short label
   (A, B, C, ...) with a legend line above the table; metric names on one
   line, else wrapped;
2. one row per metric and condition (``Metric  Condition  Value``), by
   name, else by label.

Where only the second fits and most rows hold no interval (the choice
statistics: counts and shares), those rows keep the first layout and the
rows with intervals follow in a second table. The differences table
groups its rows under each condition's name (a label where even that does
not fit). Rows that repeat others are left out with a note
(``analysis.repeats``).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, replace
from typing import Final, Literal

from rich import box
from rich.cells import cell_len
from rich.console import Console
from rich.table import Table
from rich.text import Text

from swarmtag.analysis.choice_tables import choice_notes, choice_rows
from swarmtag.analysis.choices import ConditionChoices
from swarmtag.analysis.compare import Comparison
from swarmtag.analysis.headline import INDENT, headline_lines, wrap_parts
from swarmtag.analysis.repeats import COUNT_ROWS, ShownRows, shown_rows, zero_rows
from swarmtag.analysis.summary import MetricsReport
from swarmtag.analysis.tables import (
    FLAG,
    UNDERPOWERED,
    censoring_notes,
    flag_notes,
    flagged,
    format_interval,
    format_p_value,
    metric_cells,
    metric_label,
    pa_at_delivery_notes,
    underpowered_notes,
)

__all__ = ["Grid", "condition_labels", "print_grid", "render_choices", "render_report"]

LABEL_WIDTH: Final = 16
"""The narrowest a table's first column (metric names, which may wrap) gets, but at a pinch."""
_FULL: Final = -1
"""A first column as wide as its widest line: metric names on one line."""
_PINCH: Final = 0
"""A first column as narrow as its longest word: the last resort of a narrow console."""
_P_HEADERS: Final = (
    ("p (bootstrap)", "p (Mann-Whitney)"),
    ("p (boot-\nstrap)", "p (Mann-\nWhitney)"),
)
"""Headers of the two p-value columns: on one line, else on two."""


def condition_labels(count: int) -> list[str]:
    """Short labels for ``count`` conditions: A, B, ..., Z, AA, AB, ...

    >>> condition_labels(3), condition_labels(28)[-2:]
    (['A', 'B', 'C'], ['AA', 'AB'])
    """
    labels = []
    for index in range(count):
        label, number = "", index + 1
        while number:
            number, rest = divmod(number - 1, 26)
            label = chr(ord("A") + rest) + label
        labels.append(label)
    return labels


@dataclass(frozen=True)
class Grid:
    """A table before layout: a title, the first column's header, conditions and rows."""

    title: str
    corner: str
    names: tuple[str, ...]
    rows: tuple[tuple[str, ...], ...]
    """Each row: its label, then one cell per condition."""


@dataclass(frozen=True)
class _Column:
    header: str
    cells: tuple[str, ...]
    wrap: bool = False
    """Only the first column (metric names) may wrap; numbers and names never do."""
    justify: Literal["left", "right"] = "right"


def _lines(column: _Column) -> list[str]:
    return [line for text in (column.header, *column.cells) for line in text.split("\n")]


def _label_min(column: _Column, narrowest: int) -> int:
    """The first column's least width: its widest line (``_FULL``), else at least ``narrowest``."""
    lines = _lines(column)
    widest = max(cell_len(line) for line in lines)
    if narrowest == _FULL:
        return widest
    return max([min(widest, narrowest), *(cell_len(w) for line in lines for w in line.split())])


def _table(
    title: str, columns: Sequence[_Column], narrowest: int, bold: Sequence[int] = ()
) -> Table:
    """A compact table: a rule under the header, no frame, columns three spaces apart.

    The first column gets at least ``_label_min(..., narrowest)``; ``bold``
    rows (group headings) are printed in bold.
    """
    table = Table(
        title=title,
        title_justify="left",
        box=box.SIMPLE_HEAD,
        show_edge=False,
        pad_edge=False,
    )
    for column in columns:
        if column.wrap:
            table.add_column(column.header, min_width=_label_min(column, narrowest))
        else:
            table.add_column(column.header, justify=column.justify, no_wrap=True)
    for index, row in enumerate(zip(*(column.cells for column in columns), strict=True)):
        style = "bold" if index in bold else ""
        table.add_row(*(Text(cell, style=style) for cell in row))
    return table


def _needed(columns: Sequence[_Column], narrowest: int) -> int:
    """The narrowest console that shows every cell of these columns whole.

    rich gives the first column at least its minimum width (``_label_min``)
    and every other (``no_wrap``) its longest line; the compact box puts
    three characters between columns.
    """
    total = 3 * (len(columns) - 1)
    for column in columns:
        if column.wrap:
            total += _label_min(column, narrowest)
        else:
            total += max(cell_len(line) for line in _lines(column))
    return total


def _wide(grid: Grid, heads: Sequence[str]) -> list[_Column]:
    columns = [_Column(grid.corner, tuple(row[0] for row in grid.rows), wrap=True)]
    for index, head in enumerate(heads, start=1):
        columns.append(_Column(head, tuple(row[index] for row in grid.rows)))
    return columns


def _long(grid: Grid, heads: Sequence[str]) -> list[_Column]:
    labels, names, values = [], [], []
    for label, *cells in grid.rows:
        for index, (head, cell) in enumerate(zip(heads, cells, strict=True)):
            labels.append(label if index == 0 else "")
            names.append(head)
            values.append(cell)
    return [
        _Column(grid.corner, tuple(labels), wrap=True),
        _Column("Condition", tuple(names), justify="left"),
        _Column("Value", tuple(values)),
    ]


def _print_lines(console: Console, lines: Sequence[str]) -> None:
    """Lines already wrapped to the width: printed as they are (no markup, no rewrapping)."""
    for line in lines:
        console.print(Text(line), soft_wrap=True)


def _legend(console: Console, names: Sequence[str], labels: Sequence[str]) -> None:
    parts = [f"{label} = {name}" for label, name in zip(labels, names, strict=True)]
    _print_lines(console, wrap_parts("Conditions:", parts, console.width, indent=INDENT))


@dataclass(frozen=True)
class _Layout:
    columns: list[_Column]
    narrowest: int
    """The first column's least width (``_label_min``)."""
    labelled: bool
    """Headed by labels (A, B, ...): a legend goes before the table."""
    long: bool
    """One row per metric and condition."""


def _layout(console: Console, grid: Grid) -> _Layout:
    """The first layout that fits: wide, then long; metric names on one line, then wrapped.

    Within each, by name before by label. Where nothing fits (a console
    narrower than any layout), the last: long, by label, at a pinch.
    """
    labels = condition_labels(len(grid.names))
    layouts = [
        (build, narrowest, heads)
        for build, narrowest in (
            (_wide, _FULL),
            (_wide, LABEL_WIDTH),
            (_long, _FULL),
            (_long, LABEL_WIDTH),
            (_long, _PINCH),
        )
        for heads in (grid.names, labels)
    ]
    for build, narrowest, heads in layouts:
        columns = build(grid, heads)
        if _needed(columns, narrowest) <= console.width:
            break
    return _Layout(columns, narrowest, labelled=heads is labels, long=build is _long)


def _split(console: Console, grid: Grid) -> tuple[Grid, Grid] | None:
    """The rows without intervals, and those with; ``None`` if that is no help.

    Worth it when most rows are narrow (counts, shares) and a few hold wide
    intervals: the narrow ones stay side by side, only the wide ones go long.
    """
    narrow = tuple(row for row in grid.rows if not any(" [" in cell for cell in row[1:]))
    wide = tuple(row for row in grid.rows if row not in narrow)
    if not wide or len(narrow) < len(wide):
        return None
    return replace(grid, rows=narrow), replace(grid, title=f"{grid.title}, continued", rows=wide)


def print_grid(console: Console, grid: Grid) -> None:
    """Print ``grid`` in the first layout that fits (module docstring), with a legend if labelled.

    Where only a long layout fits and most rows are narrow, the narrow rows
    keep one column per condition and the others follow in a long table.
    """
    halves = _split(console, grid) if _layout(console, grid).long else None
    legend = False
    for part in [grid] if halves is None else halves:
        layout = _layout(console, part)
        if layout.labelled and not legend:
            _legend(console, part.names, condition_labels(len(part.names)))
            legend = True
        console.print(_table(part.title, layout.columns, layout.narrowest))


def _headlines(report: MetricsReport, console: Console) -> None:
    """One headline per treatment, then the underpowered note (the tables' ``‡`` too)."""
    lines = headline_lines(report, console.width)
    if not lines:
        return
    _print_lines(console, lines)
    for note in underpowered_notes(report):
        console.print(note, highlight=False, markup=False)
    console.print()


def _value_grid(report: MetricsReport, shown: ShownRows) -> Grid:
    level = f"{report.confidence_level * 100:g} %"
    runs = "" if shown.runs_each is None else f" ({shown.runs_each} runs each)"
    rows: list[tuple[str, ...]] = []
    if shown.runs_each is None:
        rows.append(("Runs", *(str(c.kpis.runs) for c in report.conditions)))
    for metric in shown.values:
        cells = (
            [str(getattr(c.kpis, metric)) for c in report.conditions]
            if metric in COUNT_ROWS
            else metric_cells(report, metric)
        )
        rows.append((metric_label(metric, report.time_unit), *cells))
    return Grid(
        title=f"Metrics by condition{runs}: value [{level} CI]",
        corner="Metric",
        names=tuple(c.condition for c in report.conditions),
        rows=tuple(rows),
    )


def _difference_row(
    report: MetricsReport, comparison: Comparison, *, in_header: bool
) -> tuple[str, ...]:
    """One metric's difference, CI and p-values; ``in_header``: the columns' headers carry ``‡``."""
    interval = comparison.confidence_interval
    weak = f" {UNDERPOWERED}" if comparison.underpowered and not in_header else ""
    label = metric_label(comparison.metric, report.time_unit)
    return (
        f"  {label}" + (f" {FLAG}" if flagged(comparison) else ""),
        format_interval(comparison.diff, interval.low, interval.high) + weak,
        format_p_value(comparison.p_bootstrap, report.n_resamples) + weak,
        format_p_value(comparison.p_mannwhitney, report.n_resamples),
    )


def _differences(
    report: MetricsReport, shown: ShownRows, heads: Sequence[str], p_headers: tuple[str, str]
) -> tuple[list[_Column], list[int]]:
    """The differences table's columns, rows grouped under each treatment; the heading rows."""
    level = f"{report.confidence_level * 100:g} %"
    # Every comparison underpowered: one mark on each header, not on every cell (a narrow
    # terminal keeps its width for the numbers).
    in_header = all(k.underpowered for k in report.comparisons)
    mark = f" {UNDERPOWERED}" if in_header else ""
    rows: list[tuple[str, ...]] = []
    headings = []
    for statistics, head in zip(report.conditions, heads, strict=True):
        found = {k.metric: k for k in report.comparisons if k.condition == statistics.condition}
        if not found:
            continue  # the baseline
        headings.append(len(rows))
        rows.append((head, "", "", ""))
        rows += [
            _difference_row(report, found[m], in_header=in_header)
            for m in shown.differences
            if m in found
        ]
    headers = ("Metric", f"Difference [{level} CI]{mark}", p_headers[0] + mark, p_headers[1])
    columns = [
        _Column(header, tuple(row[index] for row in rows), wrap=index == 0)
        for index, header in enumerate(headers)
    ]
    return columns, headings


def _print_differences(report: MetricsReport, shown: ShownRows, console: Console) -> None:
    """The differences table in the first layout that fits: names, then labels with a legend."""
    names = [c.condition for c in report.conditions]
    labels = condition_labels(len(names))
    layouts = [
        (heads, p_headers, narrowest)
        for narrowest in (_FULL, LABEL_WIDTH, _PINCH)
        for heads, p_headers in (
            (names, _P_HEADERS[0]),
            (names, _P_HEADERS[1]),
            (labels, _P_HEADERS[1]),
        )
    ]
    for heads, p_headers, narrowest in layouts:
        columns, headings = _differences(report, shown, heads, p_headers)
        if _needed(columns, narrowest) <= console.width:
            break
    if heads is labels:
        treatments = [(label, n) for label, n in zip(labels, names, strict=True)]
        treatments = [(label, n) for label, n in treatments if n != report.baseline]
        _legend(console, [n for _, n in treatments], [label for label, _ in treatments])
    title = f"Differences from the baseline {report.baseline} (condition - baseline)"
    console.print(_table(title, columns, narrowest, bold=headings))


def _time_note(time_unit: str | None) -> str:
    if time_unit == "s":
        return "Times are in seconds (time_unit s)."
    if time_unit == "tick":
        return "Times are in simulator ticks (time_unit tick)."
    return (
        "The log does not state its time unit (no time_unit column): "
        "ticks for simulated runs, seconds for physical trials."
    )


def _notes(report: MetricsReport, shown: ShownRows) -> list[str]:
    """The lines under the tables: what was left out, what latency covers, units, resampling."""
    notes = [] if shown.note is None else [shown.note]
    if any(c.kpis.undelivered for c in report.conditions):
        undelivered = ", ".join(f"{s.condition} {s.kpis.undelivered}" for s in report.conditions)
        notes.append(
            "Latency covers delivered carriers only (undelivered carriers have none); "
            f"undelivered: {undelivered}."
        )
        notes += censoring_notes(report)
    else:
        notes += pa_at_delivery_notes(report)
    notes += flag_notes(report)
    notes.append(_time_note(report.time_unit))
    shown_metrics = {*shown.values, *shown.differences}
    for statistics in report.conditions:
        for metric in statistics.metrics:
            estimate = statistics.estimate(metric)
            missing = estimate.n_undefined
            if missing and estimate.value is not None and metric in shown_metrics:
                notes.append(
                    f"{metric_label(metric, report.time_unit)} of {statistics.condition} "
                    f"was undefined in {missing} of {report.n_resamples} resamples "
                    "(left out of its CI)."
                )
    notes.append(
        f"CIs: bootstrap over whole runs, {report.n_resamples} resamples, seed {report.seed}; "
        "p (bootstrap) = min(1, 2 min(#diff*<=0, #diff*>=0) / B); "
        "Mann-Whitney U two-sided on per-run values (KM P95 has none)."
    )
    return notes


def render_report(report: MetricsReport, console: Console) -> None:
    """Headlines, the value and differences tables, and their notes, on ``console``."""
    _headlines(report, console)
    shown = shown_rows(report)
    print_grid(console, _value_grid(report, shown))
    if report.comparisons:
        console.print()
        _print_differences(report, shown, console)
    else:
        console.print(f"Only one condition ({report.baseline}): nothing to compare.", markup=False)
    for note in _notes(report, shown):
        console.print(note, highlight=False, markup=False)


def render_choices(choices: Sequence[ConditionChoices], console: Console) -> None:
    """The choice statistics (selections, candidates, double pursuits, ...) on ``console``."""
    header, rows = choice_rows(choices)
    kept, zero = zero_rows(rows)
    console.print()
    grid = Grid(
        title="Choice statistics by condition (event table)",
        corner=header[0],
        names=tuple(header[1:]),
        rows=tuple(tuple(row) for row in kept),
    )
    print_grid(console, grid)
    notes = choice_notes(choices)
    if zero:
        notes.insert(0, f"Left out as 0 in every condition: {'; '.join(zero)}.")
    for note in notes:
        console.print(note, highlight=False, markup=False)
