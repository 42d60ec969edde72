"""The KPI window of continuous operation: the orders placed after a warm-up.

A warehouse run starts in a transient (an empty floor, robots spread from
their start cells, the first orders waiting) that says little about steady
operation. Its KPIs are those of the orders placed at or after the warm-up,
each followed to the run's end (delivered, or censored at ``run_end``).
``trim_warmup`` keeps exactly those rows, so every SPEC §5 KPI computed on
its result is the windowed KPI; nothing else changes.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from swarmtag._checks import check_instance, check_number
from swarmtag.errors import StatisticsError
from swarmtag.io.tables import CarrierLog

__all__ = ["trim_warmup", "window_note"]


def trim_warmup(log: CarrierLog, warmup: float) -> CarrierLog:
    """The rows of ``log`` ordered at or after ``warmup`` (the log's time unit), every column kept.

    A warm-up of 0 trims nothing (orders placed before the run start, which
    SPEC §8.1 allows, stay). A run left without any order is refused rather
    than dropped: dropping it would silently change the per-run means
    (deliveries per run, PA) and orphan its events in an event table.

    >>> nan = float("nan")
    >>> log = CarrierLog(condition=["c"] * 3, run=[0] * 3, seed=[0] * 3, carrier=[1, 2, 3],
    ...     urgency0=[9, 3, 5], order_time=[0.0, 70.0, 90.0], pickup_time=[5.0, 80.0, nan],
    ...     delivery_time=[9.0, 95.0, nan], robot=[0, 1, -1], run_end=[600.0] * 3)
    >>> trim_warmup(log, 60.0).carrier
    array([2, 3])
    """
    check_instance("log", log, CarrierLog, error=StatisticsError)
    start = check_number("warmup", warmup, low=0.0, error=StatisticsError)
    if start == 0.0 or len(log) == 0:
        return log
    kept = log.order_time >= start
    _check_every_run_kept(log, kept, start)
    return log.take(kept)


def _check_every_run_kept(log: CarrierLog, kept: NDArray[np.bool_], start: float) -> None:
    """Refuse a warm-up that leaves some run of some condition without a single order."""
    names, codes = np.unique(log.condition, return_inverse=True)
    runs, index = np.unique(np.stack([codes, log.run], axis=1), axis=0, return_inverse=True)
    orders_left = np.bincount(index.reshape(-1), weights=kept, minlength=len(runs))
    emptied = np.flatnonzero(orders_left == 0)
    if emptied.size == 0:
        return
    code, run = (int(value) for value in runs[emptied[0]])
    rows = (codes == code) & (log.run == run)
    latest = float(log.order_time[rows].max())
    msg = (
        f"warm-up {start:g}: run {run} of {names[code]} has no order placed at or after it "
        f"(its latest at {latest:g}); a shorter warm-up keeps every run"
    )
    raise StatisticsError(msg)


def window_note(warmup: float, unit: str) -> str:
    """The sentence tables and reports carry under a warm-up: what the KPIs cover.

    >>> window_note(60.0, "s")[:50]
    'KPIs cover the orders placed at or after 60 s (the'
    """
    return (
        f"KPIs cover the orders placed at or after {warmup:g} {unit} "
        "(the warm-up before is left out), followed to the run end."
    )
