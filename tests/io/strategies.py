"""Builders and Hypothesis strategies for event logs, shared by the io and analysis tests."""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
from hypothesis import strategies as st

from swarmtag.io import CarrierLog

Row = tuple[str, int, int, int, float, float | None]
"""condition, run, carrier, urgency0, order_time, delivery_time (None = never)."""


def log_from_rows(
    rows: Sequence[Row], *, time_unit: str | None = None, seed: int = 0
) -> CarrierLog:
    """A log from short rows: pickup one time unit before delivery (not before 0), robot 0."""
    delivery = [math.nan if row[5] is None else float(row[5]) for row in rows]
    return CarrierLog(
        condition=[row[0] for row in rows],
        run=[row[1] for row in rows],
        seed=[seed] * len(rows),
        carrier=[row[2] for row in rows],
        urgency0=[row[3] for row in rows],
        order_time=[float(row[4]) for row in rows],
        pickup_time=[d if math.isnan(d) else max(0.0, d - 1.0) for d in delivery],
        delivery_time=delivery,
        robot=[-1 if math.isnan(d) else 0 for d in delivery],
        time_unit=time_unit,
    )


@st.composite
def runs_of_carriers(
    draw: st.DrawFn, *, max_carriers: int = 9
) -> list[tuple[int, int, float, float | None]]:
    """One run: (carrier, urgency0, order_time, delivery_time or None), with plenty of ties."""
    n = draw(st.integers(1, max_carriers))
    markers = draw(st.lists(st.integers(0, 40), min_size=n, max_size=n, unique=True))
    result = []
    for marker in markers:
        urgency = draw(st.integers(0, 9))
        order = float(-draw(st.integers(0, 12)))
        delivered = draw(st.booleans() | st.just(True))
        delivery = float(draw(st.integers(0, 15))) if delivered else None
        result.append((marker, urgency, order, delivery))
    return result


@st.composite
def carrier_logs(
    draw: st.DrawFn,
    *,
    conditions: Sequence[str] = ("proximity", "urgency:alpha=0.7"),
    max_runs: int = 5,
    max_carriers: int = 9,
) -> CarrierLog:
    """A valid per-carrier log: some conditions, runs with arbitrary ids, ties and undelivered."""
    names = draw(st.lists(st.sampled_from(list(conditions)), min_size=1, unique=True))
    rows: list[Row] = []
    for name in names:
        run_ids = draw(st.lists(st.integers(0, 1000), min_size=1, max_size=max_runs, unique=True))
        for run in run_ids:
            for carrier, urgency, order, delivery in draw(
                runs_of_carriers(max_carriers=max_carriers)
            ):
                rows.append((name, run, carrier, urgency, order, delivery))
    return log_from_rows(rows, time_unit=draw(st.sampled_from([None, "tick", "s"])))


def permuted(log: CarrierLog, seed: int) -> CarrierLog:
    """The same rows in another order."""
    return log.take(np.random.default_rng(seed).permutation(len(log)))
