"""Worker process pools that Ctrl-C stops within a second, without a word from any worker.

Ctrl-C at a terminal sends SIGINT to the whole process group, workers
included. A spawned worker that gets it while it imports, or while it waits
for work, dies with a traceback on the shared stderr and breaks the pool.
So workers start with SIGINT blocked (the signal mask survives ``exec``, as
for multiprocessing's own resource tracker): the interrupt is the parent's
alone, and is held back while a worker starts. The parent then ends them
with ``stop`` instead of letting the pool wait for the jobs they are
running, which may take minutes.
"""

from __future__ import annotations

import multiprocessing
import os
import signal
from concurrent.futures import ProcessPoolExecutor
from multiprocessing.context import SpawnContext, SpawnProcess
from typing import Any

from swarmtag._interrupt import deferred

__all__ = ["spawn_context", "stop"]


class _Worker(SpawnProcess):
    """A spawned process that starts with SIGINT blocked (so it never sees a Ctrl-C)."""

    def start(self) -> None:
        # The mask is inherited by the child; in this process another thread may still take
        # the signal, so Ctrl-C is also deferred: raised once the worker is started (and in
        # active_children, where ``stop`` finds it even if the pool never recorded it).
        with deferred():
            mask = signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT})
            try:
                super().start()
            finally:
                signal.pthread_sigmask(signal.SIG_SETMASK, mask)

    def run(self) -> None:
        """The worker's work; its compiled backend runs one thread (the pool is the parallelism)."""
        os.environ.setdefault("SWARMTAG_THREADS", "1")
        super().run()


class _Context(SpawnContext):
    Process = _Worker


def spawn_context() -> multiprocessing.context.BaseContext:
    """The ``spawn`` context, its processes deaf to SIGINT (POSIX; plain spawn elsewhere)."""
    if not hasattr(signal, "pthread_sigmask"):  # pragma: no cover - Windows
        return multiprocessing.get_context("spawn")
    return _Context()


def stop(pool: ProcessPoolExecutor) -> None:
    """End the workers of ``pool`` now and shut it down (their results are not wanted).

    Every live worker of ``spawn_context`` goes, also one that a Ctrl-C kept
    the pool from recording as it started (one pool at a time is running).
    Futures are not cancelled first: Python 3.11 then fails in the pool's
    own thread (setting a broken-pool error on a cancelled future).
    """
    # The worker table is private; typed Any as it becomes None after shutdown.
    processes: Any = getattr(pool, "_processes", None)
    workers = [*(processes or {}).values()]
    workers += [p for p in multiprocessing.active_children() if isinstance(p, _Worker)]
    for process in workers:
        process.terminate()
    for process in workers:
        process.join(1.0)
        if process.is_alive():  # pragma: no cover - SIGTERM ends a worker at once
            process.kill()
            process.join()
    pool.shutdown(wait=True)
