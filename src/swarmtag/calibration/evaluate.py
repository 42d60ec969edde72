"""Evaluating points of a calibration: simulate every set-up, score it, remember it.

Every evaluation simulates the same runs (seed and run indices) of every
set-up, so two points differ only by their parameter values (common random
numbers): the objective is a deterministic function of the point. Runs are
simulated in chunks, in this process or in a pool of worker processes; a
run's rows do not depend on its chunk (SPEC §4.5), and chunks are joined in
run order, so the result does not depend on ``workers`` either.
"""

from __future__ import annotations

import math
import signal
from collections.abc import Callable, Mapping, Sequence
from concurrent.futures import FIRST_COMPLETED, Future, ProcessPoolExecutor, wait
from dataclasses import dataclass
from types import TracebackType
from typing import Final

from swarmtag._pools import spawn_context, stop
from swarmtag.calibration.cache import CacheEntry, EvaluationCache
from swarmtag.calibration.objective import Achieved, KpiFit, achieved_kpis, fit_rows, objective
from swarmtag.calibration.problem import CalibrationProblem
from swarmtag.io import CarrierLog
from swarmtag.policy import parse_policy
from swarmtag.sim import Scenario, simulate

__all__ = ["CHUNK_RUNS", "Evaluation", "Evaluator", "SimJob", "chunk_runs", "run_job"]

CHUNK_RUNS: Final = 50
"""Most runs simulated in one call (bounds memory; results do not depend on it)."""


@dataclass(frozen=True)
class SimJob:
    """Consecutive runs of one set-up at one point: everything a worker process needs."""

    point: int
    setup: str
    scenario: Scenario
    condition: str
    seed: int
    run_offset: int
    runs: int


def run_job(job: SimJob) -> CarrierLog:
    """Simulate one job (a pure function of it; runs in worker processes)."""
    result = simulate(
        job.scenario,
        parse_policy(job.condition),
        seed=job.seed,
        runs=job.runs,
        run_offset=job.run_offset,
    )
    return result.carriers


def chunk_runs(runs: int, workers: int) -> int:
    """Runs per chunk: spread over the workers, at most ``CHUNK_RUNS``.

    >>> chunk_runs(100, 1), chunk_runs(100, 8), chunk_runs(3, 8)
    (50, 13, 1)
    """
    return max(1, min(CHUNK_RUNS, math.ceil(runs / workers)))


def _ignore_interrupt() -> None:
    """Worker initialiser: Ctrl-C is the parent's to handle (it ends the workers)."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)


@dataclass(frozen=True)
class Evaluation:
    """One evaluated point: free values, achieved KPIs, the fit rows and the objective."""

    values: Mapping[str, float]
    achieved: Achieved
    rows: tuple[KpiFit, ...]
    objective: float
    cached: bool
    """Whether it came from the cache (nothing was simulated)."""


class Evaluator:
    """Evaluates points of ``problem`` through ``cache``, in ``workers`` processes.

    Use it as a context manager: the pool (``workers > 1``) starts with the
    first evaluation and is shut down on exit, its workers ended at once on an
    error or Ctrl-C; every finished point is in the cache by then.
    ``on_result`` is called with each evaluation as it finishes.
    """

    def __init__(
        self,
        problem: CalibrationProblem,
        cache: EvaluationCache,
        *,
        workers: int = 1,
        on_result: Callable[[Evaluation], None] | None = None,
    ) -> None:
        self.problem = problem
        self.cache = cache
        self.workers = max(1, workers)
        self.on_result = on_result
        self.computed = 0
        """Points simulated by this evaluator."""
        self.reused = 0
        """Points taken from the cache."""
        self._pool: ProcessPoolExecutor | None = None

    def __enter__(self) -> Evaluator:
        return self

    def __exit__(
        self,
        kind: type[BaseException] | None,
        error: BaseException | None,
        traceback: TracebackType | None,
    ) -> None:
        if self._pool is not None and kind is not None:
            self._stop()
        elif self._pool is not None:
            self._pool.shutdown(wait=True, cancel_futures=True)
            self._pool = None

    def _stop(self) -> None:
        """End the workers now: after an error or Ctrl-C their running jobs are not awaited."""
        if self._pool is not None:
            pool, self._pool = self._pool, None
            stop(pool)

    def _score(
        self, values: Mapping[str, float], achieved: Achieved, *, cached: bool
    ) -> Evaluation:
        rows = fit_rows(self.problem.targets, achieved)
        return Evaluation(values, achieved, rows, objective(rows), cached)

    def _jobs(self, index: int, values: Mapping[str, float]) -> list[SimJob]:
        problem = self.problem
        jobs: list[SimJob] = []
        for setup in problem.targets.setups:
            scenario = problem.scenario(setup, values)
            runs = problem.simulated_runs(setup)
            size = chunk_runs(runs, self.workers)
            jobs.extend(
                SimJob(
                    point=index,
                    setup=setup.name,
                    scenario=scenario,
                    condition=problem.targets.condition,
                    seed=problem.seed,
                    run_offset=start,
                    runs=min(size, runs - start),
                )
                for start in range(0, runs, size)
            )
        return jobs

    def _finish(
        self, values: Mapping[str, float], logs: Sequence[tuple[SimJob, CarrierLog]]
    ) -> Evaluation:
        """Join a point's chunks in run order, compute its KPIs, cache and report it."""
        problem = self.problem
        achieved: dict[str, dict[str, float | None]] = {}
        for setup in problem.targets.setups:
            parts = sorted(
                ((job.run_offset, log) for job, log in logs if job.setup == setup.name),
                key=lambda item: item[0],
            )
            log = CarrierLog.concat([part for _, part in parts])
            achieved[setup.name] = achieved_kpis(
                log,
                condition=problem.targets.condition,
                setup=setup,
                simulated_runs=problem.simulated_runs(setup),
            )
        evaluation = self._score(values, achieved, cached=False)
        self.cache.put(
            problem.point_key(values),
            CacheEntry(values=dict(values), achieved=achieved),
            objective=evaluation.objective,
        )
        self.computed += 1
        return evaluation

    def evaluate(self, points: Sequence[Mapping[str, float]]) -> list[Evaluation]:
        """Evaluate ``points`` (in parallel where there are workers); results in their order."""
        results: dict[int, Evaluation] = {}
        pending: dict[str, int] = {}  # key -> first index needing it
        duplicates: dict[int, int] = {}
        for index, values in enumerate(points):
            key = self.problem.point_key(values)
            entry = self.cache.get(key)
            if entry is not None:
                results[index] = self._score(values, entry.achieved, cached=True)
                self.reused += 1
                self._report(results[index])
            elif key in pending:
                duplicates[index] = pending[key]
            else:
                pending[key] = index
        todo = {index: points[index] for index in pending.values()}
        jobs = {index: self._jobs(index, values) for index, values in todo.items()}
        if self.workers == 1 or sum(len(batch) for batch in jobs.values()) <= 1:
            for index, batch in jobs.items():
                results[index] = self._finish(todo[index], [(job, run_job(job)) for job in batch])
                self._report(results[index])
        elif jobs:
            results.update(self._in_pool(todo, jobs))
        for index, first in duplicates.items():
            results[index] = results[first]
        return [results[index] for index in range(len(points))]

    def _report(self, evaluation: Evaluation) -> None:
        if self.on_result is not None:
            self.on_result(evaluation)

    def _in_pool(
        self, todo: Mapping[int, Mapping[str, float]], jobs: Mapping[int, list[SimJob]]
    ) -> dict[int, Evaluation]:
        """Run every job in the pool; finish each point as soon as all its chunks are in."""
        if self._pool is None:
            # Spawned workers share nothing with us and leave Ctrl-C to us (see _pools).
            self._pool = ProcessPoolExecutor(
                max_workers=self.workers, mp_context=spawn_context(), initializer=_ignore_interrupt
            )
        waiting = {index: len(batch) for index, batch in jobs.items()}
        done: dict[int, list[tuple[SimJob, CarrierLog]]] = {index: [] for index in jobs}
        futures: dict[Future[CarrierLog], SimJob] = {
            self._pool.submit(run_job, job): job for batch in jobs.values() for job in batch
        }
        results: dict[int, Evaluation] = {}
        remaining = set(futures)
        try:
            while remaining:
                finished, remaining = wait(remaining, return_when=FIRST_COMPLETED)
                for future in sorted(finished, key=lambda f: _order(futures[f])):
                    job = futures[future]
                    done[job.point].append((job, future.result()))
                    waiting[job.point] -= 1
                    if waiting[job.point] == 0:
                        results[job.point] = self._finish(todo[job.point], done[job.point])
                        self._report(results[job.point])
        except BaseException:
            self._stop()
            raise
        return results


def _order(job: SimJob) -> tuple[int, str, int]:
    return job.point, job.setup, job.run_offset
