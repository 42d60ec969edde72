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
    rows: Sequence[Row],
    *,
    time_unit: str | None = None,
    seed: int = 0,
    run_end: Sequence[float | None] | None = None,
    urgency_end: Sequence[int | None] | None = None,
) -> CarrierLog:
    """A log from short rows: pickup one time unit before delivery (not before 0), robot 0.

    ``run_end`` and ``urgency_end``, if given, hold one value (or None) per row.
    """
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
        run_end=None if run_end is None else [math.nan if e is None else e for e in run_end],
        urgency_end=None if urgency_end is None else [-1 if u is None else u for u in urgency_end],
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
    """A valid per-carrier log: some conditions, runs with arbitrary ids, ties and undelivered.

    Some logs have ``run_end`` (for some runs or all, at or after the run's
    last event) and ``urgency_end`` (for some rows or all).
    """
    names = draw(st.lists(st.sampled_from(list(conditions)), min_size=1, unique=True))
    with_run_end, with_urgency_end = draw(st.booleans()), draw(st.booleans())
    rows: list[Row] = []
    ends: list[float | None] = []
    urgencies: list[int | None] = []
    for name in names:
        run_ids = draw(st.lists(st.integers(0, 1000), min_size=1, max_size=max_runs, unique=True))
        for run in run_ids:
            carriers = draw(runs_of_carriers(max_carriers=max_carriers))
            latest = max((d for *_, d in carriers if d is not None), default=0.0)
            end = float(latest + draw(st.integers(0, 6)))
            given = with_run_end and draw(st.booleans() | st.just(True))
            for carrier, urgency, order, delivery in carriers:
                rows.append((name, run, carrier, urgency, order, delivery))
                ends.append(end if given else None)
                urgencies.append(
                    draw(st.integers(0, 9) | st.just(urgency) | st.none())
                    if with_urgency_end
                    else None
                )
    return log_from_rows(
        rows,
        time_unit=draw(st.sampled_from([None, "tick", "s"])),
        run_end=ends if with_run_end else None,
        urgency_end=urgencies if with_urgency_end else None,
    )


def permuted(log: CarrierLog, seed: int) -> CarrierLog:
    """The same rows in another order."""
    return log.take(np.random.default_rng(seed).permutation(len(log)))
