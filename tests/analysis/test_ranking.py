"""Ranking many conditions: order by PA, the Pareto front, messages per delivery, the figure."""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest
from PIL import Image

from swarmtag.analysis import MetricsReport, summarize
from swarmtag.analysis.figures import pareto_figure
from swarmtag.analysis.ranking import rank_conditions, ranking_html, ranking_markdown
from swarmtag.errors import BackendFallback
from swarmtag.io import CarrierLog, EventTable
from swarmtag.policy import parse_policy
from swarmtag.sim import Scenario, simulate

WORLD = Scenario.from_mapping(
    {**Scenario.default(5, 10, profile="paper-sim").to_mapping(), "ticks": 1500}
)
NAMES = ("proximity", "edf", "cbaa:comm_range=10,loss=0.1")


@pytest.fixture(scope="module")
def ranked() -> tuple[MetricsReport, EventTable]:
    """The summary and events of four runs of each condition: simulated once for the module."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", BackendFallback)
        results = [simulate(WORLD, parse_policy(name), seed=2, runs=4) for name in NAMES]
    log = CarrierLog.concat([r.carriers for r in results])
    events = EventTable.concat([r.events for r in results])
    return summarize(log, n_resamples=200, seed=1), events


def test_conditions_are_ranked_by_pa_and_the_front_is_the_undominated_set(ranked):
    report, events = ranked
    rows = rank_conditions(report, events)
    assert [row.rank for row in rows] == [1, 2, 3]
    pa = [row.pa.value for row in rows]
    assert pa == sorted(pa, reverse=True)
    points = [(row.pa.value, row.throughput.value) for row in rows]
    for row, (p, t) in zip(rows, points, strict=True):
        beaten = any(
            (q >= p and u >= t) and (q > p or u > t) for q, u in points if (q, u) != (p, t)
        )
        assert row.pareto is not beaten
    assert rows[0].pareto  # the best PA is never dominated


def test_messages_per_delivery_are_the_messages_over_the_deliveries(ranked):
    report, events = ranked
    rows = {row.condition: row for row in rank_conditions(report, events)}
    cbaa = parse_policy(NAMES[2]).name
    mine = events.condition == cbaa
    expected = events.value[mine & (events.kind == "messages")].sum() / np.count_nonzero(
        mine & (events.kind == "deliver")
    )
    assert math.isclose(rows[cbaa].messages_per_delivery, expected)
    assert rows["proximity"].messages_per_delivery is None
    table = ranking_markdown(list(rows.values()), "5x10", time_unit="tick")
    assert "Throughput (per 100 ticks) [95 % CI]" in table
    assert "| - |" in table
    assert "<table>" in ranking_html(list(rows.values()), time_unit="tick")


def test_the_pareto_figure_is_a_real_picture(ranked, tmp_path):
    report, events = ranked
    rows = rank_conditions(report, events)
    path = tmp_path / "pareto.png"
    pareto_figure({"5x10": rows, "again": rows}, path, time_unit="tick")
    with Image.open(path) as image:
        assert image.format == "PNG"
        assert image.size[0] > 2 * image.size[1]  # two panels side by side
        assert len(image.convert("RGB").getcolors(maxcolors=1_000_000) or []) > 50
