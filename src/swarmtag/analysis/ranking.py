"""Ranking many conditions: PA, throughput, P95, messages per delivery, the Pareto front.

A study that compares many rules (the allocators study) asks which is best,
and there is no one answer: urgency adherence and throughput pull apart.
The table ranks the conditions by PA (the project's question), ties by
throughput, and marks the **Pareto-optimal** ones: no other condition has a
PA and a throughput at least as large, one of them larger. Messages per
delivery are the ``messages`` events' sum over the ``deliver`` events, both
over whole runs (a warehouse's warm-up included; allocators that talk, ``-``
for the others).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from swarmtag.analysis.bootstrap import Estimate
from swarmtag.analysis.summary import MetricsReport
from swarmtag.analysis.tables import (
    format_interval,
    format_number,
    html_table,
    markdown_table,
    metric_label,
)
from swarmtag.io import EventTable

__all__ = ["RankRow", "rank_conditions", "ranking_html", "ranking_markdown"]


def _header(time_unit: str | None) -> tuple[str, ...]:
    return (
        "rank",
        "condition",
        "PA [95 % CI]",
        f"{metric_label('throughput', time_unit)} [95 % CI]",
        f"{metric_label('p95_latency', time_unit)} [95 % CI]",
        "messages per delivery",
        "Pareto-optimal",
    )


@dataclass(frozen=True)
class RankRow:
    """One condition's place in the ranking."""

    rank: int
    condition: str
    pa: Estimate
    throughput: Estimate
    p95: Estimate
    messages_per_delivery: float | None
    """None for a condition that sent no messages."""
    pareto: bool


def _value(estimate: Estimate) -> float:
    value = estimate.value
    return -math.inf if value is None or math.isnan(value) else value


def rank_conditions(report: MetricsReport, events: EventTable | None = None) -> list[RankRow]:
    """Every condition of ``report``, best PA first (ties: throughput), Pareto front marked.

    ``events`` (the same runs' event table) gives the messages per delivery.
    """
    rows = []
    for statistics in report.conditions:
        messages = None
        if events is not None:
            mine = events.condition == statistics.condition
            sent = mine & (events.kind == "messages")
            if sent.any():
                delivered = int((mine & (events.kind == "deliver")).sum())
                total = float(events.value[sent].sum())
                messages = total / delivered if delivered else math.inf
        rows.append(
            (
                statistics.condition,
                statistics.estimate("pa"),
                statistics.estimate("throughput"),
                statistics.estimate("p95_latency"),
                messages,
            )
        )
    points = np.array([(_value(pa), _value(tp)) for _, pa, tp, _, _ in rows])
    ranked = sorted(range(len(rows)), key=lambda i: (-points[i, 0], -points[i, 1], rows[i][0]))
    result = []
    for place, i in enumerate(ranked, start=1):
        name, pa, throughput, p95, messages = rows[i]
        dominated = bool(
            (
                (points[:, 0] >= points[i, 0])
                & (points[:, 1] >= points[i, 1])
                & ((points[:, 0] > points[i, 0]) | (points[:, 1] > points[i, 1]))
            ).any()
        )
        result.append(RankRow(place, name, pa, throughput, p95, messages, not dominated))
    return result


def _cells(row: RankRow) -> list[str]:
    def interval(estimate: Estimate) -> str:
        ci = estimate.confidence_interval
        return format_interval(estimate.value, ci.low, ci.high)

    messages = (
        "-" if row.messages_per_delivery is None else format_number(row.messages_per_delivery)
    )
    return [
        str(row.rank),
        row.condition,
        interval(row.pa),
        interval(row.throughput),
        interval(row.p95),
        messages,
        "yes" if row.pareto else "",
    ]


def ranking_markdown(rows: Sequence[RankRow], title: str, *, time_unit: str | None) -> str:
    """The ranking as a Markdown table under ``title``."""
    table = markdown_table(_header(time_unit), [_cells(row) for row in rows])
    return f"### {title}\n\n{table}\n"


def ranking_html(rows: Sequence[RankRow], *, time_unit: str | None) -> str:
    """The ranking as an HTML table."""
    return html_table(_header(time_unit), [_cells(row) for row in rows])
