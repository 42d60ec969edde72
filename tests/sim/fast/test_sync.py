"""Threads meeting in compiled code: atomic counts lose nothing, barriers order writes."""

from concurrent.futures import ThreadPoolExecutor

import numba
import numpy as np
import pytest

from swarmtag.sim.fast._sync import SYNC_ABORT, SYNC_SIZE, atomic_add, barrier, sync_array

ROUNDS = 20_000


@numba.njit(cache=False, nogil=True)  # not cached: it would keep old _sync code
def _add_ones(counts: np.ndarray, rounds: int) -> int:
    """``counts[0] += 1`` ``rounds`` times, atomically; the largest value seen before an add."""
    seen = -1
    for _ in range(rounds):
        seen = max(seen, atomic_add(counts, 0, 1))
    return seen


@numba.njit(cache=False, nogil=True)  # not cached: it would keep old _sync code
def _rounds_in_step(sync: np.ndarray, written: np.ndarray, part: int, parts: int) -> int:
    """Each round every thread writes its entry, then checks the others' after a barrier.

    Returns the rounds done (``-1 - round`` at the first wrong value seen).
    """
    for done in range(ROUNDS):
        written[part] = done + 1
        if not barrier(sync, parts):
            return done
        for other in range(parts):
            if written[other] != done + 1:
                return -1 - done
        if not barrier(sync, parts):  # nobody writes the next round before all have read
            return done
    return ROUNDS


def test_atomic_adds_on_two_threads_lose_no_count():
    counts = np.zeros(1, dtype=np.int64)
    with ThreadPoolExecutor(2) as pool:
        seen = list(pool.map(lambda _: _add_ones(counts, ROUNDS), range(2)))
    assert counts[0] == 2 * ROUNDS
    assert max(seen) == 2 * ROUNDS - 1


@pytest.mark.parametrize("parts", [1, 2, 3])
def test_threads_at_a_barrier_see_each_others_writes(parts):
    sync = sync_array()
    assert sync.shape == (SYNC_SIZE,)
    written = np.zeros(parts, dtype=np.int64)
    with ThreadPoolExecutor(parts) as pool:
        done = list(
            pool.map(lambda part: _rounds_in_step(sync, written, part, parts), range(parts))
        )
    assert done == [ROUNDS] * parts
    assert (written == ROUNDS).all()


def test_an_abort_releases_threads_waiting_for_one_that_never_comes():
    sync = sync_array()
    written = np.zeros(3, dtype=np.int64)
    with ThreadPoolExecutor(2) as pool:  # parts 0 and 1 of three: they wait for part 2
        futures = [pool.submit(_rounds_in_step, sync, written, part, 3) for part in (0, 1)]
        sync[SYNC_ABORT] = 1
        assert [future.result(timeout=60) for future in futures] == [0, 0]
