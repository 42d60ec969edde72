"""The choice table: one row set for every format, unknown shares shown as unknown."""

from __future__ import annotations

from swarmtag.analysis import choice_statistics
from swarmtag.analysis.choice_tables import (
    choice_rows,
    choices_html,
    choices_latex,
    choices_markdown,
)
from swarmtag.io import EventTable
from tests.analysis.test_choices import table


def _choices():
    known = table([(0, 1.0, "select", 1, 0, 5.0), (0, 1.0, "candidates", 1, 0, 4.0)])
    unknown = table([(0, 1.0, "select", 1, 0, 5.0), (0, 3.0, "timeout", 1, 0, 1.0)], condition="d")
    return choice_statistics(EventTable.concat([known, unknown]), n_resamples=40, seed=1)


def test_rows_hold_every_statistic_per_condition():
    header, rows = choice_rows(_choices())
    assert header == ["Choice statistic", "c", "d"]
    by_label = {row[0]: row[1:] for row in rows}
    assert by_label["Selections"] == ["1", "1"]
    assert by_label["Share among 3+ candidates"] == ["1.000", "unknown"]
    assert by_label["Share among 1 candidate"] == ["0", "unknown"]
    assert by_label["Mean candidates per selection"] == ["4.000", "unknown"]
    assert by_label["Timeouts per run [95 % CI]"] == ["0 [0, 0]", "1.000 [1.000, 1.000]"]
    assert by_label["Timeouts (total)"] == ["0", "1"]
    assert len(rows) == 3 + 3 + 1 + 4 + 4


def test_every_format_carries_the_same_cells():
    choices = _choices()
    _, rows = choice_rows(choices)
    markdown, latex, html = choices_markdown(choices), choices_latex(choices), choices_html(choices)
    for row in rows:
        assert "| " + " | ".join(row) + " |" in markdown
    assert html.count("<tr>") == len(rows) + 1
    assert r"Share among 3+ candidates & 1.000 & unknown \\" in latex
    assert "% CIs: bootstrap over whole runs, 40 resamples, seed 1." in latex
    assert html.endswith("40 resamples, seed 1.</p>")
