"""One line per treatment: its key differences from the baseline, the first thing to read.

``urgency:alpha=0.7 vs proximity: PA +0.1775 [0.0925, 0.2600] p<0.0002;
P95 -280.8 [-485.1, -10.62] ticks p=0.0388; throughput -0.6 % p=0.821``

The figures are the report's comparisons (``diff = condition - baseline``,
its bootstrap CI and bootstrap p), in the tables' number format, so a
headline and the differences table never disagree. Throughput is shown as
the relative change against the baseline's throughput (its p is the
difference's). Where the two conditions left different shares of carriers
undelivered, delivered-only P95 is biased (``tables.flagged``): the headline
then shows the censored P95 and the two undelivered counts. An underpowered
comparison (fewer than ``MIN_RUNS`` runs) marks each p with ``UNDERPOWERED``,
as the tables do. Pure: a report in, strings out.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Final

from swarmtag.analysis.compare import Comparison
from swarmtag.analysis.summary import MetricsReport
from swarmtag.analysis.tables import (
    UNDERPOWERED,
    flagged,
    format_number,
    format_p_value,
    unit_word,
)

__all__ = [
    "INDENT",
    "headline",
    "headline_lines",
    "p_text",
    "signed",
    "wrap_parts",
]

INDENT: Final = "    "
"""Continuation lines of a headline (or a legend) start with this."""
_SEPARATOR: Final = "; "


def signed(value: float | None) -> str:
    """A difference in the tables' format with its sign spelled out: ``+0.1775``, ``-280.8``.

    >>> signed(0.17752), signed(-280.84), signed(0.0), signed(None)
    ('+0.1775', '-280.8', '0', 'n/a')
    """
    text = format_number(value)
    return f"+{text}" if value is not None and value > 0 else text


def p_text(comparison: Comparison, resamples: int) -> str:
    """``p=0.0388`` or ``p<0.0002`` (below the resolution 2/B), ``‡`` when underpowered."""
    value = format_p_value(comparison.p_bootstrap, resamples)
    text = f"p{value.replace(' ', '')}" if value.startswith("<") else f"p={value}"
    return text + (UNDERPOWERED if comparison.underpowered else "")


def _interval(comparison: Comparison) -> str:
    interval = comparison.confidence_interval
    if interval.low is None or interval.high is None:
        return signed(comparison.diff)
    bounds = f"[{format_number(interval.low)}, {format_number(interval.high)}]"
    return f"{signed(comparison.diff)} {bounds}"


def _relative(report: MetricsReport, comparison: Comparison) -> str:
    """The difference as a percentage of the baseline's value, ``n/a`` where undefined."""
    base = report.condition(comparison.baseline).kpis.value(comparison.metric)
    if comparison.diff is None or base is None or base == 0:
        return "n/a"
    if comparison.diff == 0:
        return "0.0 %"
    return f"{100 * comparison.diff / base:+.1f} %"


def headline(report: MetricsReport, condition: str) -> tuple[str, list[str]]:
    """The lead (``NAME vs BASELINE:``) and the parts of one treatment's headline.

    Each part is one metric (or the undelivered counts) and is never split
    when the headline is wrapped (``wrap_parts``).
    """
    found = {k.metric: k for k in report.comparisons if k.condition == condition}
    unit = unit_word(report.time_unit)
    resamples = report.n_resamples
    parts = []
    undelivered = []
    if "pa" in found:
        k = found["pa"]
        parts.append(f"PA {_interval(k)} {p_text(k, resamples)}")
    if "p95_latency" in found:
        k = found["p95_latency"]
        if flagged(k) and "p95_latency_censored" in found:
            censored = found["p95_latency_censored"]
            parts.append(f"P95 censored {_interval(censored)} {unit} {p_text(censored, resamples)}")
            undelivered.append(f"undelivered {k.undelivered[0]} vs {k.undelivered[1]}")
        else:
            parts.append(f"P95 {_interval(k)} {unit} {p_text(k, resamples)}")
    if "throughput" in found:
        k = found["throughput"]
        parts.append(f"throughput {_relative(report, k)} {p_text(k, resamples)}")
    return f"{condition} vs {report.baseline}:", parts + undelivered


def wrap_parts(lead: str, parts: Sequence[str], width: int, *, indent: str = INDENT) -> list[str]:
    """``lead`` and ``parts`` joined by ``; `` in lines of at most ``width``, never mid-part.

    A line that must hold a part longer than ``width`` holds it alone (and
    overflows) rather than cutting it.

    >>> wrap_parts("a vs b:", ["PA +0.1 [0.05, 0.2] p=0.01", "P95 -3 [-5, -1] s p=0.02"], 40)
    ['a vs b: PA +0.1 [0.05, 0.2] p=0.01;', '    P95 -3 [-5, -1] s p=0.02']
    """
    lines: list[str] = []
    line = lead
    for index, part in enumerate(parts):
        piece = part + (_SEPARATOR.rstrip() if index < len(parts) - 1 else "")
        joined = f"{line} {piece}" if line else piece
        if len(joined) <= width or not line:
            line = joined
        else:
            lines.append(line)
            line = indent + piece
    lines.append(line)
    return lines


def headline_lines(report: MetricsReport, width: int) -> list[str]:
    """Every treatment's headline, wrapped to ``width`` (none with a single condition)."""
    lines = []
    for statistics in report.conditions:
        if statistics.condition == report.baseline:
            continue
        lead, parts = headline(report, statistics.condition)
        lines += wrap_parts(lead, parts, width)
    return lines
