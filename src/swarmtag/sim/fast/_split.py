"""One large run on several threads: every thread steps its ticks, meeting at barriers.

``_tick.tick_run`` does a run's tick in one call, and the runner spreads runs
over threads. A batch of fewer runs than threads with many robots (one
warehouse, a million robots) instead has every thread call ``split_ticks``
at once; each tick is

0. (thread 0, a call's first tick only) the tick's random numbers (one
   generator per stream and run); read only by step 2, so the last thread
   draws the next tick's during step 5;
1. (thread 0) the robots' start, the run's index of obstacles, the
   advertising tags; thread 1 builds the robots' index meanwhile;
2. (every thread, a range of robots each) sense, break down, decide, move:
   each robot reads the tick's start and writes only its own entries;
3. (thread 0) bodies and the first collision pass's robots; with the
   robots' grid, every thread then copies a range of robots to their grid
   slots;
4. (every thread, a range each) the first pass's new positions (it reads
   only the positions at the pass's start);
5. (thread 0) the first pass's update, the other passes (few robots), and
   every phase after the collisions.

The threads wait for each other between the steps at ``_sync.barrier``, in
compiled code (handing the steps out from Python cost a quarter of a
20,000-robot tick). Each thread's ``Scratch`` has query buffers (``gathered``,
``near_*``) of its own (``thread_scratch``); everything else is shared. The
result is ``tick_run``'s, bit for bit: no sum changes its order.
"""

from __future__ import annotations

from typing import Final

import numpy as np

from swarmtag.sim.fast._events import room_for_tick
from swarmtag.sim.fast._index import copy_to_slots, index_robots
from swarmtag.sim.fast._jit import entry, inlined
from swarmtag.sim.fast._layout import Constants, Scratch, World
from swarmtag.sim.fast._motion import collide_range, resolve_begin, resolve_finish
from swarmtag.sim.fast._sync import SYNC_VALUES, barrier
from swarmtag.sim.fast._tick import draw, tick_begin, tick_end, tick_robots

__all__ = ["SYNC_DRAWN", "split_ticks", "thread_scratch"]

SYNC_GO: Final = SYNC_VALUES
"""1 while the run steps on (thread 0 decides before each tick)."""
SYNC_DRAWN: Final = SYNC_VALUES + 1
"""The tick whose random numbers the buffers hold (-1: none yet)."""
SYNC_ACTIVE: Final = SYNC_VALUES + 2
"""Robots of the tick's first collision pass (step 3 to step 4)."""


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
    """Part ``part`` of ``0 .. count`` cut into ``parts`` contiguous ranges (as ``_ranges``)."""
    return count * part // parts, count * (part + 1) // parts


@entry
def split_ticks(
    part: int,
    parts: int,
    r: int,
    stop: int,
    turns: np.ndarray,
    first: int,
    motion: np.random.Generator,
    breakdown: np.random.Generator,
    radio: np.random.Generator,
    camera: np.random.Generator,
    sync: np.ndarray,
    w: World,
    k: Constants,
    x: Scratch,
) -> None:
    """Thread ``part`` of ``parts``: run ``r`` tick by tick to ``stop``, its end or a full buffer.

    Every thread calls this at once with its own ``x`` (``thread_scratch``)
    and the same ``sync`` (``_sync.sync_array``; ``sync[SYNC_DRAWN]``: the
    tick whose random numbers the buffers hold, kept between calls). Thread
    0 does the steps of one thread, the last thread draws the next tick's
    numbers during step 5 (see the module docs).
    Returns early, without finishing its tick, if another thread will not
    come (``SYNC_ABORT``).
    """
    room = k.robots + k.pickup_slots.shape[0]
    lo, hi = _part(k.robots, part, parts)
    while True:
        if part == 0:
            go = w.ended_at[r] < 0 and w.run_tick[r] < stop and x.failure[r] == 0
            sync[SYNC_GO] = 1 if go and room_for_tick(r, room, x) else 0
        if not barrier(sync, parts) or sync[SYNC_GO] == 0:
            return
        t = w.run_tick[r] + 1
        row = t - first if k.walk_turn_ticks > 0 else 0
        if part == 0:  # step 0 here only for a call's first tick: later, step 5 drew it
            if sync[SYNC_DRAWN] != t:
                draw(r, motion, breakdown, radio, camera, k, x)
                sync[SYNC_DRAWN] = t
            tick_begin(r, t, parts == 1, w, k, x)  # one part: no thread 1 to index
        elif part == 1:
            index_robots(r, w, k, x)
        if not barrier(sync, parts):
            return
        tick_robots(r, t, lo, hi, turns, row, w, k, x)
        if not barrier(sync, parts):
            return
        if part == 0:
            sync[SYNC_ACTIVE] = resolve_begin(r, False, w, k, x)
        if not barrier(sync, parts):
            return
        if k.robot_grid:
            copy_to_slots(r, lo, hi, x)
            if not barrier(sync, parts):
                return
        count = sync[SYNC_ACTIVE]
        pass_lo, pass_hi = _part(count, part, parts)
        collide_range(r, pass_lo, pass_hi, True, w, k, x)
        if not barrier(sync, parts):
            return
        if part == parts - 1:  # tick t + 1's numbers, read only by its step 2
            draw(r, motion, breakdown, radio, camera, k, x)
            sync[SYNC_DRAWN] = t + 1
        if part == 0:
            resolve_finish(r, count, w, k, x)
            tick_end(r, t, w, k, x)
            w.run_tick[r] = t
