"""Compile (or load) one of the fast kernel's two entry points, so the tests start with both cached.

``python -m tests.kernel_warmup batched|split``: ``tests/conftest.py`` runs
both at once in two processes before any test, so that the two first
compilations (a minute or two each on one core) overlap, every test worker
then loads machine code instead of compiling it again, and a command-line
test never meets the first-compilation note on stderr.
"""

from __future__ import annotations

import sys
from dataclasses import replace

from swarmtag.policy import Urgency
from swarmtag.sim import Scenario, simulate

ENTRIES = ("batched", "split")
"""The kernel's entry points: ``_tick.advance`` (runs on threads) and ``_split.split_ticks``."""


def warm(entry: str) -> None:
    """Run two ticks through ``entry``: numba compiles it, or loads it from its cache."""
    scenario = replace(Scenario.default(3, 7), ticks=2)
    if entry == "batched":
        simulate(scenario, Urgency(alpha=0.7), seed=0, runs=1, backend="fast", threads=1)
        return
    from swarmtag.sim.fast import _runner  # numba only where it is installed

    _runner.SPLIT_FROM = 1  # a run of 3 robots on two threads takes the split path
    simulate(scenario, Urgency(alpha=0.7), seed=0, runs=1, backend="fast", threads=2)


if __name__ == "__main__":
    if len(sys.argv) != 2 or sys.argv[1] not in ENTRIES:
        sys.exit(f"usage: python -m tests.kernel_warmup {'|'.join(ENTRIES)}")
    warm(sys.argv[1])
