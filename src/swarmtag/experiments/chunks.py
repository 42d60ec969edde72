"""Chunks: the unit of work of a study (consecutive runs of one condition on one scale).

A ``ChunkJob`` carries everything needed to compute it, so it can be pickled
to a worker process or a Dask worker; ``simulate_chunk`` is a pure function
of the job. ``split_runs`` turns a sorted list of missing runs into chunks.
"""

from __future__ import annotations

from collections.abc import Iterator, Sequence
from dataclasses import dataclass
from numbers import Integral

from swarmtag._checks import check_instance, check_int, check_sequence, show
from swarmtag.errors import StudyError
from swarmtag.experiments.store import RunKey
from swarmtag.io import CarrierLog, EventTable
from swarmtag.policy import load_rule, parse_policy
from swarmtag.sim import Scenario, simulate

__all__ = ["ChunkJob", "ChunkResult", "simulate_chunk", "split_runs"]

ChunkResult = tuple[CarrierLog, EventTable]
"""A chunk's carrier log and event table, as ``simulate`` returns them."""


@dataclass(frozen=True, kw_only=True)
class ChunkJob:
    """One unit of work: ``runs`` consecutive runs from ``run_offset`` of one condition.

    Holds everything a worker needs (it is pickled to worker processes) and
    the store key its results go under.
    """

    key: RunKey
    scenario: Scenario
    condition: str
    run_offset: int
    runs: int
    backend: str | None = None
    """Simulation backend (``None``: the default, ``fast`` where numba is installed)."""
    threads: int | None = None
    """Threads of the compiled backend (``None``: every core)."""
    rules: tuple[str, ...] = ()
    """Score rule files (``FILE.py:FUNCTION``) a worker loads before reading the condition."""


def simulate_chunk(job: ChunkJob) -> ChunkResult:
    """Simulate one chunk; a pure function of the job (run in worker processes)."""
    check_instance("job", job, ChunkJob, error=StudyError)
    for spec in job.rules:  # a spawned worker has not loaded the study's rule files
        load_rule(spec)
    result = simulate(
        job.scenario,
        parse_policy(job.condition),
        seed=job.key.seed,
        runs=job.runs,
        run_offset=job.run_offset,
        backend=job.backend,
        threads=job.threads,
    )
    return result.carriers, result.events


def split_runs(runs: Sequence[int], size: int) -> Iterator[tuple[int, int]]:
    """``(offset, count)`` spans of consecutive runs, at most ``size`` each, covering ``runs``.

    >>> list(split_runs([0, 1, 2, 3, 4, 7, 8], 2))
    [(0, 2), (2, 2), (4, 1), (7, 2)]
    """
    items = check_sequence("runs", runs, error=StudyError)
    for run in items:
        if isinstance(run, bool) or not isinstance(run, Integral) or run < 0:
            msg = f"runs: {show(run)} is not a run index (an integer >= 0)"
            raise StudyError(msg)
    size = check_int("size", size, low=1, error=StudyError)
    return _spans([int(run) for run in items], size)


def _spans(runs: Sequence[int], size: int) -> Iterator[tuple[int, int]]:
    start = 0
    while start < len(runs):
        end = start + 1
        while end < len(runs) and end - start < size and runs[end] == runs[end - 1] + 1:
            end += 1
        yield runs[start], end - start
        start = end
