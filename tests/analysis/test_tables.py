"""Markdown/LaTeX tables and the signed scalability table."""

from __future__ import annotations

import pytest

from swarmtag.analysis import summarize
from swarmtag.analysis.tables import (
    format_interval,
    format_number,
    format_p_value,
    latex_tables,
    markdown_tables,
    relative_change,
    scalability_table,
)
from swarmtag.data import example_trial
from swarmtag.errors import StatisticsError
from swarmtag.io import parse_carrier_csv


@pytest.fixture(scope="module")
def report():
    return summarize(parse_carrier_csv(example_trial().read_text()), n_resamples=500, seed=1)


@pytest.mark.parametrize(
    ("value", "text"),
    [(3271.5, "3272"), (0.34752, "0.3475"), (12.345, "12.35"), (-45.8, "-45.80"), (0.0, "0"),
     (700, "700"), (float("nan"), "n/a"), (None, "n/a")],
)  # fmt: skip
def test_format_number(value, text):
    assert format_number(value) == text


def test_format_interval_and_p():
    assert format_interval(1.5, 1.0, 2.25) == "1.500 [1.000, 2.250]"
    assert format_interval(1.5, None, None) == "1.500"
    assert format_p_value(0.0, 2000) == "< 0.001"
    assert format_p_value(None, 2000) == "n/a"


def test_markdown_tables_hold_every_metric_and_comparison(report):
    text = markdown_tables(report)
    value_table, diff_table, note = text.strip().split("\n\n")
    rows = value_table.splitlines()
    assert rows[0] == "| Metric | proximity | urgency:alpha=3.0 |"
    # header, rule, five metrics, totals, undelivered, three censoring-aware latencies
    assert len(rows) == 2 + 5 + 2 + 3
    assert [row.split(" | ")[0] for row in rows[-3:]] == [
        "| P95 latency, censored (s)",
        "| Mean latency, censored (s)",
        "| KM P95 latency (s)",
    ]
    pa = report.condition("urgency:alpha=3.0").pa
    expected = format_interval(pa.value, pa.confidence_interval.low, pa.confidence_interval.high)
    assert "| PA (5-50 %) | " in value_table
    assert expected in value_table
    assert len(diff_table.splitlines()) == 2 + 8
    assert "urgency:alpha=3.0 | PA (5-50 %)" in diff_table
    # Undelivered 1 vs 2: the delivered-only latency rows carry the flag, the censored ones not.
    assert "urgency:alpha=3.0 | P95 latency (s) \N{DAGGER} |" in diff_table
    assert "urgency:alpha=3.0 | Mean latency (s) \N{DAGGER} |" in diff_table
    assert "urgency:alpha=3.0 | P95 latency, censored (s) |" in diff_table
    assert "undelivered: proximity 2, urgency:alpha=3.0 1" in note
    assert note.splitlines()[-1] == (
        "\N{DAGGER} urgency:alpha=3.0: undelivered differs from proximity (1 vs 2): "
        "delivered-only latency is biased; compare the censored rows."
    )
    assert "Runs without run_end in the log (proximity 12, urgency:alpha=3.0 12)" in note


def test_latex_tables_escape_and_balance(report):
    text = latex_tables(report)
    assert text.count(r"\begin{tabular}") == text.count(r"\end{tabular}") == 2
    assert r"PA (5-50 \%)" in text
    assert r"P95 latency (s) \textsuperscript{\dag}" in text
    # Table cells are escaped; the notes are comments, where UTF-8 text is harmless.
    assert all("\N{DAGGER}" not in line for line in text.splitlines() if not line.startswith("%"))
    assert "5-50 %)" not in text.replace(r"\%", "")
    for line in text.splitlines():
        if line.endswith(r"\\"):
            assert line.count("&") in (2, 4)  # 3 columns in the value table, 5 in the other


@pytest.mark.parametrize(
    ("metric", "base", "value", "change"),
    [("p95_latency", 200.0, 150.0, 0.25), ("p95_latency", 100.0, 120.0, -0.2),
     ("pa", 0.4, 0.5, 0.25), ("total_deliveries", 80, 60, -0.25), ("pa", 0.0, 0.5, None),
     ("pa", None, 0.5, None)],
)  # fmt: skip
def test_relative_change_is_positive_when_better(metric, base, value, change):
    result = relative_change(metric, base, value)
    assert result == (None if change is None else pytest.approx(change))


def test_relative_change_refuses_unknown_metrics():
    with pytest.raises(StatisticsError, match="throughput"):
        relative_change("throughput", 1.0, 2.0)


def test_scalability_table(report):
    text = scalability_table({"3/7": report}, condition="urgency:alpha=3.0")
    table, note = text.strip().split("\n\n")
    rows = table.splitlines()
    assert len(rows) == 2 + 6
    assert note.startswith("\N{DAGGER} 3/7: undelivered differs (1 vs 2)")
    assert rows[3].startswith("| 3/7 | Undelivered carriers | 2 | 1 | +50.0 % |")  # fewer: better
    assert "| 3/7 | P95 latency (s) \N{DAGGER} |" in table
    base = report.condition("proximity").kpis
    other = report.condition("urgency:alpha=3.0").kpis
    expected = 100 * (base.p95_latency - other.p95_latency) / base.p95_latency
    assert f"{expected:+.1f} %" in rows[4]
    assert rows[2].startswith(
        f"| 3/7 | Total deliveries | {base.total_deliveries} | {other.total_deliveries} |"
    )
    assert r"\toprule" in scalability_table(
        {"3/7": report}, condition="urgency:alpha=3.0", markdown=False
    )
