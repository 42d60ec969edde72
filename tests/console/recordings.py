"""Recorded runs for the replay tests: a hand-made event log, and a real MCAP run."""

from __future__ import annotations

import subprocess
from pathlib import Path

from swarmtag.io import CarrierLog, write_event_log
from tests.console.server_process import SWARMTAG

NAN = float("nan")
MCAP_TICKS = 1000
"""Ticks of the MCAP run: long enough for its first deliveries."""
TICK = 0.5
"""Seconds per tick the tests replay a log in ticks with (``--tick 0.5``)."""


def two_runs() -> CarrierLog:
    """Two runs of three carriers, in ticks: run 0 lasts 100 ticks (50 s), run 1 60 ticks.

    Run 0: carrier 0 ordered before the start, picked up by robot 1 at 10,
    delivered at 30 (urgency 9 then); carrier 1 ordered at 20, picked up at 50,
    never delivered; carrier 2 ordered at 70 and left waiting. Run 1: carrier
    0 delivered at 40 by robot 0.
    """
    return CarrierLog(
        condition=["urgency:alpha=0.7"] * 6,
        run=[0, 0, 0, 1, 1, 1],
        seed=[0] * 6,
        carrier=[0, 1, 2, 0, 1, 2],
        urgency0=[5, 3, 7, 2, 4, 6],
        order_time=[-10.0, 20.0, 70.0, 0.0, 0.0, 0.0],
        pickup_time=[10.0, 50.0, NAN, 20.0, NAN, NAN],
        delivery_time=[30.0, NAN, NAN, 40.0, NAN, NAN],
        robot=[1, -1, -1, 0, -1, -1],
        time_unit="tick",
        run_end=[100.0, 100.0, 100.0, 60.0, 60.0, 60.0],
        urgency_end=[9, -1, -1, 3, -1, -1],
    )


def write_log(folder: Path, name: str = "run.csv") -> Path:
    """``two_runs`` written to ``folder/name`` (.csv or .parquet)."""
    path = folder / name
    write_event_log(two_runs(), path)
    return path


def simulate_mcap(folder: Path) -> Path:
    """A ``MCAP_TICKS`` run of the default scenario written by ``swarmtag simulate --mcap``."""
    path = folder / "run.mcap"
    subprocess.run(
        [str(SWARMTAG), "simulate", "--runs", "1", "--ticks", str(MCAP_TICKS), "--condition",
         "urgency:alpha=0.7", "--resamples", "1", "--mcap", str(path)],
        check=True, capture_output=True, timeout=300,
    )  # fmt: skip
    return path
