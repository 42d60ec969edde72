"""One large run on several threads: every thread steps its ticks, meeting at barriers.

``_tick.tick_run`` does a run's tick in one call, and the runner spreads runs
over threads. A batch of fewer runs than threads with many robots (one
warehouse, a million robots) instead has every thread call ``split_ticks``
at once; each tick is

1. (thread 0) the robots' start, the run's index of obstacles, the
   advertising tags;
2. (every thread, a range of robots each) sense, break down, decide, move:
   each robot reads the tick's start and its random numbers, and writes
   only its own entries;
3. (thread 0) bodies and the first collision pass's robots; with the
   robots' grid, every thread then copies a range of robots to their grid
   slots;
4. (every thread, a range each) the first pass's new positions (it reads
   only the positions at the pass's start);
5. (thread 0) the first pass's update, the other passes (few robots);
   then (every thread, a range each, thread 0 alone for who drives in,
   smallest id first) the robots' positions, arrivals and docking
   (``_settle``: the last moves of the tick);
6. (thread 0) every later phase (``tick_finish``), while thread 1 builds
   the robots' index of the next tick (they stand where it starts), so
   that step 1 of the next tick is short (the index of a run's first
   tick is built in its step 1).

The threads wait for each other between the steps at barriers, in compiled
code (``_sync``; handing the steps out from Python cost a quarter of a
20,000-robot tick). Only step 2 reads the tick's random numbers, so the next
tick's are drawn from the end of step 2 to the start of the next step 2, in
chunks (``_draws``), by whichever thread waits at a barrier meanwhile: one
thread at a time (a token), in the streams' order, so the numbers are those
of one thread drawing them all; before step 2, every thread draws until none
is left. Each thread's ``Scratch`` has query buffers (``gathered``,
``near_*``) of its own (``thread_scratch``); everything else is shared. The
result is ``tick_run``'s, bit for bit: no sum changes its order.
"""

from __future__ import annotations

from typing import Final

import numpy as np

from swarmtag.sim.fast._collide import (
    collide_range,
    drop_ghosts,
    resolve_begin,
    resolve_passes,
    settle_positions,
)
from swarmtag.sim.fast._docking import (
    arrive_clocks,
    arrive_drive_in,
    arrive_requests,
    dock_robots,
)
from swarmtag.sim.fast._draws import DRAW_CHUNK, chunk_end, draw_range, draw_units
from swarmtag.sim.fast._events import room_for_tick
from swarmtag.sim.fast._index import copy_to_slots, index_robots
from swarmtag.sim.fast._jit import entry, glue, inlined
from swarmtag.sim.fast._layout import Constants, World
from swarmtag.sim.fast._scratch import Scratch
from swarmtag.sim.fast._sync import (
    SYNC_ABORT,
    SYNC_LINE,
    SYNC_VALUES,
    arrive,
    atomic_add,
    atomic_load,
    atomic_store,
    barrier,
    passed,
    pause,
    sync_array,
)
from swarmtag.sim.fast._tick import outside_row, start_call, tick_begin, tick_finish, tick_robots

__all__ = ["SYNC_DRAWN", "SYNC_INDEXED", "split_sync", "split_ticks", "thread_scratch"]

SYNC_GO: Final = SYNC_VALUES
"""1 while the run steps on (thread 0 decides before each tick)."""
SYNC_DRAWN: Final = SYNC_VALUES + 1
"""The tick whose random numbers the buffers hold, or are being drawn for (-1: none yet)."""
SYNC_ACTIVE: Final = SYNC_VALUES + 2
"""Robots of the tick's first collision pass (step 3 to step 4)."""
SYNC_INDEXED: Final = SYNC_VALUES + 3
"""The tick whose robots' index is built (thread 1 builds it at the end of the tick before;
-1: none). Kept between calls: nothing moves a robot between them."""
SYNC_DRAW_AT: Final = SYNC_VALUES + SYNC_LINE
"""Units of ``SYNC_DRAWN``'s numbers drawn so far (``_draws``; all of them at or past
``draw_units``)."""
SYNC_DRAW_TOKEN: Final = SYNC_DRAW_AT + 1
"""Non-zero while a thread draws (or tries to take the turn)."""
_ALL_DRAWN: Final = 1 << 62
"""``SYNC_DRAW_AT`` of a tick whose numbers are all in the buffers, whatever the units."""


def split_sync(drawn: int, indexed: int) -> np.ndarray:
    """A ``sync`` array for ``split_ticks``: the buffers hold all of tick ``drawn``'s numbers.

    ``indexed``: the tick whose robots' index is built (``SYNC_INDEXED``).
    """
    sync = sync_array()
    sync[SYNC_DRAWN] = drawn
    sync[SYNC_INDEXED] = indexed
    sync[SYNC_DRAW_AT] = _ALL_DRAWN
    return sync


def thread_scratch(x: Scratch) -> Scratch:
    """``x`` with query buffers of its own, for a second thread on the same runs."""
    return x._replace(
        gathered=np.zeros_like(x.gathered),
        near_carriers=np.zeros_like(x.near_carriers),
        near_blockers=np.zeros_like(x.near_blockers),
        near_robots=np.zeros_like(x.near_robots),
    )


@inlined
def _part(count: int, part: int, parts: int) -> tuple[int, int]:
    """Part ``part`` of ``0 .. count`` cut into ``parts`` contiguous ranges."""
    return count * part // parts, count * (part + 1) // parts


@inlined
def _draw_chunk(
    r: int,
    streams: np.ndarray,
    sync: np.ndarray,
    k: Constants,
    x: Scratch,
) -> bool:
    """Draw the next chunk of ``SYNC_DRAWN``'s numbers if none are left to another thread.

    False if all are drawn or another thread has the turn (the caller waits).
    """
    units = draw_units(k)
    if atomic_load(sync, SYNC_DRAW_AT) >= units:
        return False
    if atomic_add(sync, SYNC_DRAW_TOKEN, 1) != 0:
        atomic_add(sync, SYNC_DRAW_TOKEN, -1)
        return False
    first = atomic_load(sync, SYNC_DRAW_AT)
    if first < units:  # another thread may have drawn the last chunk meanwhile
        stop = chunk_end(first, DRAW_CHUNK, k)
        draw_range(r, first, stop, streams, k, x)
        atomic_store(sync, SYNC_DRAW_AT, stop)
    atomic_add(sync, SYNC_DRAW_TOKEN, -1)
    return True


@inlined
def _meet(
    parts: int,
    r: int,
    streams: np.ndarray,
    sync: np.ndarray,
    k: Constants,
    x: Scratch,
) -> bool:
    """``_sync.barrier``, drawing the next tick's numbers while waiting (after step 2 only)."""
    round_now = arrive(sync, parts)
    spins = 0
    state = passed(sync, round_now)
    while state == 0:
        if not _draw_chunk(r, streams, sync, k, x):
            spins = pause(spins)
        state = passed(sync, round_now)
    return state > 0


@inlined
def _draw_rest(
    r: int,
    streams: np.ndarray,
    sync: np.ndarray,
    k: Constants,
    x: Scratch,
) -> bool:
    """Draw with the other threads until ``SYNC_DRAWN``'s numbers are all drawn.

    False if a thread will not come (``SYNC_ABORT``).
    """
    spins = 0
    units = draw_units(k)
    while atomic_load(sync, SYNC_DRAW_AT) < units:
        if atomic_load(sync, SYNC_ABORT) != 0:
            return False
        if not _draw_chunk(r, streams, sync, k, x):
            spins = pause(spins)
    return True


@glue
def _first_pass(
    part: int,
    parts: int,
    r: int,
    streams: np.ndarray,
    sync: np.ndarray,
    w: World,
    k: Constants,
    x: Scratch,
) -> int:
    """Steps 3 and 4: the first collision pass; its robots, or -1 if a thread will not come."""
    if part == 0:
        sync[SYNC_ACTIVE] = resolve_begin(r, True, w, k, x)
    if not _meet(parts, r, streams, sync, k, x):
        return -1
    if k.robot_grid:
        lo, hi = _part(k.robots, part, parts)
        copy_to_slots(r, lo, hi, x)
        if not _meet(parts, r, streams, sync, k, x):
            return -1
    count: int = sync[SYNC_ACTIVE]
    pass_lo, pass_hi = _part(count, part, parts)
    collide_range(r, pass_lo, pass_hi, True, w, k, x)
    if not _meet(parts, r, streams, sync, k, x):
        return -1
    return count


@glue
def _settle(
    part: int,
    parts: int,
    r: int,
    t: int,
    count: int,
    streams: np.ndarray,
    sync: np.ndarray,
    w: World,
    k: Constants,
    x: Scratch,
) -> bool:
    """Step 5: the later collision passes (thread 0), then arrivals and docking, a range each.

    ``_tick.tick_settle`` after ``_motion.resolve_finish``, cut where a loop
    over the robots reads what another robot's range wrote. False if a
    thread will not come.
    """
    lo, hi = _part(k.robots, part, parts)
    if part == 0:
        resolve_passes(r, count, w, k, x)
    if not _meet(parts, r, streams, sync, k, x):
        return False
    settle_positions(r, lo, hi, w, k, x)
    if not _meet(parts, r, streams, sync, k, x):  # ghosts read carriers other ranges moved
        return False
    drop_ghosts(r, lo, hi, w, k, x)
    arrive_clocks(r, lo, hi, 4 * t, w, k, x)
    if not _meet(parts, r, streams, sync, k, x):  # drive-in reads every robot's mark
        return False
    if part == 0:
        arrive_drive_in(r, 4 * t, w, k, x)
    if not _meet(parts, r, streams, sync, k, x):
        return False
    arrive_requests(r, lo, hi, w, k, x)
    dock_robots(r, lo, hi, w, x)
    return True


@entry
def split_ticks(
    part: int,
    parts: int,
    r: int,
    stop: int,
    outside: np.ndarray,
    first: int,
    streams: np.ndarray,
    sync: np.ndarray,
    w: World,
    k: Constants,
    x: Scratch,
) -> None:
    """Thread ``part`` of ``parts``: run ``r`` tick by tick to ``stop``, its end or a full buffer.

    Every thread calls this at once with its own ``x`` (``thread_scratch``)
    and the same ``sync`` (``split_sync``; ``sync[SYNC_DRAWN]``: the tick
    whose random numbers the buffers hold, all drawn when the call returns,
    kept between calls). Thread 0 does the steps of one thread (see the
    module docs). Returns early, without finishing its tick, if another
    thread will not come (``SYNC_ABORT``).
    """
    room = k.robots + k.pickup_slots.shape[0]
    lo, hi = _part(k.robots, part, parts)
    if part == 0:
        start_call(r, x)
    while True:
        if part == 0:
            go = w.ended_at[r] < 0 and w.run_tick[r] < stop and x.failure[r] == 0
            go = go and room_for_tick(r, room, x)
            sync[SYNC_GO] = 1 if go else 0
            if go and sync[SYNC_DRAWN] != w.run_tick[r] + 1:  # a call's first tick, not drawn
                sync[SYNC_DRAWN] = w.run_tick[r] + 1
                atomic_store(sync, SYNC_DRAW_AT, 0)
        if not _meet(parts, r, streams, sync, k, x) or sync[SYNC_GO] == 0:
            # the next tick's numbers all drawn before a pause (at once on SYNC_ABORT)
            _draw_rest(r, streams, sync, k, x)
            return
        t = w.run_tick[r] + 1
        row = outside_row(t, first, k)
        if part == 0:
            tick_begin(r, t, parts == 1, w, k, x)  # one part: no thread 1 to index
        elif part == 1 and sync[SYNC_INDEXED] != t:  # a run's first tick
            index_robots(r, w, k, x)
        drawn = _draw_rest(r, streams, sync, k, x)
        if not (drawn and barrier(sync, parts)):
            return
        tick_robots(r, t, lo, hi, outside, row, w, k, x)
        if part == 0:  # tick t + 1's numbers may be drawn once step 2 is over
            sync[SYNC_DRAWN] = t + 1
            atomic_store(sync, SYNC_DRAW_AT, 0)
        if not barrier(sync, parts):  # no drawing here: step 2 still reads the numbers
            return
        count = _first_pass(part, parts, r, streams, sync, w, k, x)
        if count < 0:
            return
        if not _settle(part, parts, r, t, count, streams, sync, w, k, x):
            return
        if parts > 1:  # the robots stand where tick t + 1 starts: thread 1 indexes them
            if not _meet(parts, r, streams, sync, k, x):
                return
            if part == 1:
                index_robots(r, w, k, x)
                sync[SYNC_INDEXED] = t + 1  # read by this thread, and the runner after the call
        if part == 0:
            tick_finish(r, t, w, k, x)
            w.run_tick[r] = t
