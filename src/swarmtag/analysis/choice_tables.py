"""Choice statistics as tables: one column per condition, the same rows everywhere.

The terminal (``swarmtag metrics``, ``swarmtag simulate``), Markdown, LaTeX
and HTML all take their cells from ``choice_rows``, so they cannot disagree.
Shares and the mean number of candidates read ``unknown`` where no selection
has a ``candidates`` event (never 0).
"""

from __future__ import annotations

import html
from collections.abc import Sequence
from typing import Final

from swarmtag.analysis.choices import CHOICE_COUNTS, ConditionChoices
from swarmtag.analysis.tables import (
    _latex,
    format_interval,
    format_number,
    html_table,
    markdown_table,
)

__all__ = [
    "UNKNOWN",
    "choice_notes",
    "choice_rows",
    "choices_html",
    "choices_latex",
    "choices_markdown",
]

UNKNOWN: Final = "unknown"
"""The cell of a share or mean that no ``candidates`` event informs."""
_COUNT_LABELS: Final = {
    "double_pursuits": "Double pursuits",
    "timeouts": "Timeouts",
    "abandons": "Abandons",
    "lift_refused": "Refused lifts",
}


def _known(value: float | None) -> str:
    return UNKNOWN if value is None else format_number(value)


def choice_rows(choices: Sequence[ConditionChoices]) -> tuple[list[str], list[list[str]]]:
    """Header (``Choice statistic``, then the conditions) and rows of the choice table."""
    header = ["Choice statistic", *(c.condition for c in choices)]
    level = f"{choices[0].confidence_level * 100:g} %" if choices else "95 %"
    rows = [
        ["Runs", *(str(c.n_runs) for c in choices)],
        ["Selections", *(str(c.total("selections")) for c in choices)],
        ["Selections with a candidate count", *(str(c.total("known")) for c in choices)],
    ]
    for index, label in enumerate(("1 candidate", "2 candidates", "3+ candidates")):
        rows.append(
            [
                f"Share among {label}",
                *(_known(None if c.shares is None else c.shares[index]) for c in choices),
            ]
        )
    rows.append(["Mean candidates per selection", *(_known(c.mean_candidates) for c in choices)])
    for name in CHOICE_COUNTS:
        cells = []
        for c in choices:
            estimate = c.per_run[name]
            interval = estimate.confidence_interval
            cells.append(format_interval(estimate.value, interval.low, interval.high))
        rows.append([f"{_COUNT_LABELS[name]} per run [{level} CI]", *cells])
    rows += [
        [f"{_COUNT_LABELS[name]} (total)", *(str(c.total(name)) for c in choices)]
        for name in CHOICE_COUNTS
    ]
    return header, rows


def choice_notes(choices: Sequence[ConditionChoices]) -> list[str]:
    """What the rows mean, in a few lines (the definitions are in docs/metrics.md)."""
    notes = [
        (
            "Shares and the mean count are over selections with a candidates event "
            f"({UNKNOWN} where there is none). A double pursuit is a selection of a carrier "
            "another robot is already pursuing (from its select until its abandon, timeout, "
            "breakdown, lift or refused lift)."
        )
    ]
    if choices:
        first = choices[0]
        notes.append(
            f"CIs: bootstrap over whole runs, {first.n_resamples} resamples, seed {first.seed}."
        )
    return notes


def choices_markdown(choices: Sequence[ConditionChoices]) -> str:
    """The choice table as Markdown, then its notes."""
    header, rows = choice_rows(choices)
    return markdown_table(header, rows) + "\n\n" + "\n".join(choice_notes(choices)) + "\n"


def choices_latex(choices: Sequence[ConditionChoices]) -> str:
    """The choice table as a LaTeX ``tabular`` (booktabs rules), then its notes as comments."""
    header, rows = choice_rows(choices)
    notes = "\n".join("% " + note for note in choice_notes(choices))
    return _latex(header, rows) + "\n\n" + notes + "\n"


def choices_html(choices: Sequence[ConditionChoices]) -> str:
    """The choice table as an HTML ``<table>``, then its notes."""
    header, rows = choice_rows(choices)
    notes = [f'<p class="note">{html.escape(note)}</p>' for note in choice_notes(choices)]
    return "\n".join([html_table(header, rows), *notes])
