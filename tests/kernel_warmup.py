"""Compile (or load) the fast kernel's entry points and the bootstrap's compiled loops.

``python -m tests.kernel_warmup batched|split|statistics``:
``tests/conftest.py`` runs all three at once in separate processes before
any test, so that the first compilations (a minute or two each on one core
for the kernel's entry points, a few seconds for the statistics) overlap,
every test worker then loads machine code instead of compiling it again,
and a command-line test never meets the first-compilation note on stderr.
``make demo`` runs ``batched`` and ``statistics`` during its install.
"""

from __future__ import annotations

import sys
from dataclasses import replace

import numpy as np

from swarmtag.analysis import summarize
from swarmtag.io import CarrierLog
from swarmtag.policy import Urgency
from swarmtag.sim import Scenario, simulate

ENTRIES = ("batched", "split", "statistics")
"""The kernel's entry points (``_tick.advance``, which runs on threads, and
``_split.split_ticks``) and the bootstrap's compiled loops (``analysis._compiled``)."""


def warm(entry: str) -> None:
    """Run two ticks through ``entry``: numba compiles it, or loads it from its cache."""
    if entry == "statistics":
        summarize(_mixed_log(), n_resamples=200, compiled=True)
        return
    scenario = replace(Scenario.default(3, 7), ticks=2)
    if entry == "batched":
        simulate(scenario, Urgency(alpha=0.7), seed=0, runs=1, backend="fast", threads=1)
        return
    from swarmtag.sim.fast import _runner  # numba only where it is installed

    _runner.SPLIT_FROM = 1  # a run of 3 robots on two threads takes the split path
    simulate(scenario, Urgency(alpha=0.7), seed=0, runs=1, backend="fast", threads=2)


def _mixed_log(runs: int = 12, carriers: int = 7) -> CarrierLog:
    """Two conditions of ``runs`` x ``carriers``, about one carrier in forty undelivered.

    Censored carriers, but few enough that the Kaplan-Meier P95 is defined:
    so every compiled loop of a real summary runs, with a real summary's
    argument types (``tests/test_kernel_warmup.py`` checks that none is left).
    """
    rows = 2 * runs * carriers
    draws = np.random.default_rng(0)
    order = draws.uniform(0, 80, rows)
    pickup = order + draws.uniform(1, 25, rows)
    delivery = pickup + draws.uniform(1, 25, rows)
    delivery[draws.random(rows) < 1 / 40] = np.nan
    pickup[np.isnan(delivery) & (draws.random(rows) < 0.5)] = np.nan
    return CarrierLog(
        condition=np.repeat(["proximity", "urgency:alpha=0.7"], runs * carriers).tolist(),
        run=np.tile(np.repeat(np.arange(runs), carriers), 2),
        seed=np.zeros(rows, dtype=np.int64),
        carrier=np.tile(np.arange(carriers), 2 * runs),
        urgency0=draws.integers(1, 10, rows),
        order_time=order,
        pickup_time=pickup,
        delivery_time=delivery,
        robot=np.where(np.isnan(pickup), -1, 0),
        run_end=np.full(rows, 130.0),
    )


if __name__ == "__main__":
    if len(sys.argv) != 2 or sys.argv[1] not in ENTRIES:
        sys.exit(f"usage: python -m tests.kernel_warmup {'|'.join(ENTRIES)}")
    warm(sys.argv[1])
