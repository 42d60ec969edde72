"""The headline per treatment: the comparison's own numbers, wrapped without cutting a figure."""

from __future__ import annotations

import pytest

from swarmtag.analysis import summarize
from swarmtag.analysis.headline import INDENT, headline, headline_lines, p_text, signed, wrap_parts
from swarmtag.analysis.tables import UNDERPOWERED, format_number
from swarmtag.data import example_trial
from swarmtag.io import CarrierLog, parse_carrier_csv


@pytest.fixture(scope="module")
def trial():
    """The example trial: 12 runs each, undelivered 2 vs 1 (delivered-only latency flagged)."""
    return summarize(parse_carrier_csv(example_trial().read_text()), n_resamples=500, seed=1)


def _log(runs: int) -> CarrierLog:
    """Two conditions, every carrier delivered; urgency-first delivers urgent carrier 2 first."""
    rows: dict[str, list] = {k: [] for k in ("condition", "run", "carrier", "delivery_time")}
    for condition, slow in (("proximity", 60.0), ("urgency:alpha=0.7", 5.0)):
        for run in range(runs):
            for carrier, delivery in ((1, 10.0 + run), (2, slow + run), (3, 40.0 + 2 * run)):
                rows["condition"].append(condition)
                rows["run"].append(run)
                rows["carrier"].append(carrier)
                rows["delivery_time"].append(delivery)
    count = len(rows["run"])
    return CarrierLog(
        condition=rows["condition"],
        run=rows["run"],
        seed=[0] * count,
        carrier=rows["carrier"],
        urgency0=[9 if c == 2 else 1 for c in rows["carrier"]],
        order_time=[0.0] * count,
        pickup_time=[d - 1 for d in rows["delivery_time"]],
        delivery_time=rows["delivery_time"],
        robot=[0] * count,
    )


def _figure(comparison) -> str:
    interval = comparison.confidence_interval
    return (
        f"{signed(comparison.diff)} [{format_number(interval.low)}, {format_number(interval.high)}]"
    )


def test_headline_holds_the_comparisons_numbers():
    report = summarize(_log(12), n_resamples=400, seed=2)
    found = {k.metric: k for k in report.comparisons}
    lead, parts = headline(report, "urgency:alpha=0.7")
    assert lead == "urgency:alpha=0.7 vs proximity:"
    pa, p95, throughput = parts
    assert found["pa"].diff > 0  # the urgent carrier now comes first, not last
    assert pa == f"PA {_figure(found['pa'])} {p_text(found['pa'], 400)}"
    assert pa.startswith(f"PA +{format_number(found['pa'].diff)} [")
    assert (
        p95 == f"P95 {_figure(found['p95_latency'])} time units {p_text(found['p95_latency'], 400)}"
    )
    base = report.condition("proximity").kpis.throughput
    change = 100 * found["throughput"].diff / base
    assert throughput == f"throughput {change:+.1f} % {p_text(found['throughput'], 400)}"
    assert UNDERPOWERED not in "".join(parts)  # 12 runs each


def test_p_text_reads_like_the_tables():
    report = summarize(_log(12), n_resamples=400, seed=2)
    pa = next(k for k in report.comparisons if k.metric == "pa")
    assert pa.p_bootstrap == 0  # every resample puts alpha=0.7 ahead
    assert p_text(pa, 400) == "p<0.005"
    deliveries = next(k for k in report.comparisons if k.metric == "deliveries_per_run")
    assert p_text(deliveries, 400) == "p=1"


def test_few_runs_mark_each_p_underpowered():
    report = summarize(_log(3), n_resamples=200)
    _, parts = headline(report, "urgency:alpha=0.7")
    assert all(part.endswith(UNDERPOWERED) for part in parts)


def test_flagged_latency_shows_the_censored_p95_and_the_undelivered_counts(trial):
    found = {k.metric: k for k in trial.comparisons}
    assert found["p95_latency"].undelivered_differs
    lead, parts = headline(trial, "urgency:alpha=3.0")
    assert lead == "urgency:alpha=3.0 vs proximity:"
    censored = found["p95_latency_censored"]
    assert parts[1] == f"P95 censored {_figure(censored)} s {p_text(censored, 500)}"
    assert parts[-1] == "undelivered 1 vs 2"
    assert not any(part.startswith("P95 ") and "censored" not in part for part in parts)


def test_headline_lines_fit_80_columns_and_keep_every_part_whole(trial):
    lines = headline_lines(trial, 80)
    assert lines[0].startswith("urgency:alpha=3.0 vs proximity: PA +")
    assert all(len(line) <= 80 for line in lines)
    assert all(line.startswith(INDENT) for line in lines[1:])
    _, parts = headline(trial, "urgency:alpha=3.0")
    text = "\n".join(lines)
    assert all(part in text for part in parts)  # no part was cut at a line break
    assert headline_lines(trial, 1000) == ["urgency:alpha=3.0 vs proximity: " + "; ".join(parts)]


def test_one_condition_has_no_headline():
    only = _log(10).take(_log(10).condition == "proximity")
    assert headline_lines(summarize(only, n_resamples=50), 80) == []


@pytest.mark.parametrize("width", [20, 40, 60, 80, 120])
def test_wrap_parts_never_splits_a_part(width):
    parts = ["PA +0.1775 [0.0925, 0.2600] p<0.0002", "P95 -280.8 [-485.1, -10.62] ticks p=0.0388"]
    lines = wrap_parts("urgency:alpha=0.7 vs proximity:", parts, width)
    pieces = [line.strip().removesuffix(";") for line in lines]
    for part in parts:
        assert sum(part in piece for piece in pieces) == 1
    for line in lines:  # a line overflows only to hold one part (or the lead) whole
        assert len(line) <= width or line.strip().removesuffix(";") in [*parts, lines[0]]
    assert all(line.startswith(INDENT) for line in lines[1:])
