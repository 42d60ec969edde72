"""Where chunks are computed: this process, a local process pool, or a Dask distributed cluster.

Every backend calls ``simulate_chunk`` on each job and hands the result to
``on_done`` **in this process**, which stores it; workers never touch the
results store. Results are the same on every backend because a chunk's
result depends only on the job.
"""

from __future__ import annotations

import importlib
from collections.abc import Callable, Sequence
from concurrent.futures import Future, ProcessPoolExecutor, as_completed
from typing import Any, Final

from swarmtag._pools import spawn_context, stop
from swarmtag.errors import StudyError
from swarmtag.experiments.chunks import ChunkJob, ChunkResult, simulate_chunk

__all__ = ["DASK_EXTRA", "OnDone", "run_dask", "run_local"]

OnDone = Callable[[ChunkJob, ChunkResult], None]
"""Called in the parent process with each finished job and its logs."""
DASK_EXTRA: Final = "--scheduler needs the 'experiments' extra: pip install 'swarmtag[experiments]'"


def run_local(jobs: Sequence[ChunkJob], workers: int, on_done: OnDone) -> None:
    """Run ``jobs`` in this process (one worker) or in a pool of ``workers`` processes."""
    if workers == 1 or len(jobs) <= 1:
        for job in jobs:
            on_done(job, simulate_chunk(job))
        return
    # Spawned workers share nothing with this process (no forked database handle), and
    # leave Ctrl-C to it: on an error or an interrupt they are ended at once.
    with ProcessPoolExecutor(max_workers=workers, mp_context=spawn_context()) as pool:
        try:
            futures: dict[Future[ChunkResult], ChunkJob] = {
                pool.submit(simulate_chunk, job): job for job in jobs
            }
            for future in as_completed(futures):
                on_done(futures[future], future.result())
        except BaseException:
            stop(pool)
            raise


def run_dask(jobs: Sequence[ChunkJob], address: str, on_done: OnDone) -> None:
    """Run ``jobs`` on the Dask distributed scheduler at ``address`` (``tcp://host:8786``).

    The workers need swarmtag installed at the same version (the store keys
    runs by it, but a worker with other code would compute other numbers).
    """
    try:
        # Typed Any: distributed is untyped, and an optional extra imported on first use.
        distributed: Any = importlib.import_module("distributed")
    except ImportError:  # pragma: no cover - the extra is installed in the test environment
        raise StudyError(DASK_EXTRA) from None
    try:
        # The connect timeout is Dask's setting distributed.comm.timeouts.connect (30 s).
        client = distributed.Client(address, set_as_default=False)
    except OSError as error:
        msg = f"--scheduler: cannot reach a Dask scheduler at {address!r} ({error})"
        raise StudyError(msg) from None
    # as_current: as_completed finds the client without making it the process-wide default.
    with client, client.as_current():
        if not jobs:
            return
        futures = client.map(simulate_chunk, list(jobs), pure=False)
        owner = {future.key: job for future, job in zip(futures, jobs, strict=True)}
        try:
            for future, result in distributed.as_completed(futures, with_results=True):
                on_done(owner[future.key], result)
        except BaseException:
            client.cancel(futures)
            raise
