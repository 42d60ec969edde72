"""Threads for computing: how many (``SWARMTAG_THREADS``, else the usable cores), and a map on them.

The compiled simulation backend runs a batch's runs on ``default_threads()``
threads; ``summarize`` runs its conditions' bootstraps on as many. Worker
processes set ``SWARMTAG_THREADS=1`` (``swarmtag._pools``): the pool is then
the parallelism, and processes and threads do not compete for the cores.
"""

from __future__ import annotations

import os
from collections.abc import Callable, Sequence
from concurrent.futures import Future, ThreadPoolExecutor
from concurrent.futures import TimeoutError as FutureTimeout
from typing import TypeVar

from swarmtag._interrupt import RESEND_S, checkpoint

__all__ = ["default_threads", "map_in_threads"]

T = TypeVar("T")
R = TypeVar("R")


def default_threads() -> int:
    """Threads to compute on: ``SWARMTAG_THREADS`` (a whole number >= 1), else the usable cores."""
    text = os.environ.get("SWARMTAG_THREADS", "")
    if text.isdigit() and int(text) >= 1:
        return int(text)
    if hasattr(os, "sched_getaffinity"):
        return len(os.sched_getaffinity(0))
    return os.cpu_count() or 1


def _result(future: Future[R]) -> R:
    """``future``'s result; while it waits, a Ctrl-C that something swallowed is raised here."""
    while True:
        try:
            return future.result(timeout=RESEND_S)
        except FutureTimeout:
            checkpoint()


def map_in_threads(work: Callable[[T], R], items: Sequence[T], threads: int) -> list[R]:
    """``[work(item) for item in items]``, the items shared out over up to ``threads`` threads.

    The results come in the order of ``items``, and the first error (in that
    order) is raised. ``work`` must give the same result whichever thread
    runs it, and when. With one thread, or one item, everything runs in this
    thread. On an error or a Ctrl-C the items not started are dropped; those
    running end on their own (a bootstrap at its next chunk, where a Ctrl-C
    was flagged) without being waited for.
    """
    if threads <= 1 or len(items) <= 1:
        return [work(item) for item in items]
    pool = ThreadPoolExecutor(min(threads, len(items)), thread_name_prefix="swarmtag-compute")
    try:
        futures = [pool.submit(work, item) for item in items]
        return [_result(future) for future in futures]
    finally:
        pool.shutdown(wait=False, cancel_futures=True)
