"""One large run on several threads: a tick in up to eight kernel calls, three split by robots.

``_tick.tick_run`` does a run's tick in one call, and the runner spreads runs
over threads. A batch of fewer runs than threads with many robots (one
warehouse, a million robots) instead steps each tick as

0. ``split_draw`` (one thread): the tick's random numbers (one generator per
   stream and run). Read only by step 2, so the runner draws the next
   tick's while this tick's steps 5 and the next tick's step 1 run;
1. ``split_begin`` (one thread): the robots' start, the run's index of
   obstacles and robots, the advertising tags; in the largest runs
   ``split_index_robots`` builds the robots' index on another thread
   meanwhile;
2. ``split_robots`` on ranges of robots at once: sense, break down, decide,
   move (each robot reads the tick's start and writes only its own entries);
3. ``split_collide_begin`` (one thread): bodies and the first collision
   pass's robots; with the robots' grid, each robot is copied to its grid
   slot, here or, in the largest runs, by ``split_copy`` on ranges of
   robots at once;
4. ``split_collide`` on ranges of those at once: the first pass's new
   positions (it reads only the positions at the pass's start);
5. ``split_finish`` (one thread): the first pass's update, the other passes
   (few robots), and every phase after the collisions.

Each thread's calls get a ``Scratch`` whose query buffers (``gathered``,
``near_*``) are its own (``thread_scratch``); everything else is shared.
The result is ``tick_run``'s, bit for bit: no sum changes its order.
"""

from __future__ import annotations

import numpy as np

from swarmtag.sim.fast._index import copy_to_slots, index_robots
from swarmtag.sim.fast._jit import entry
from swarmtag.sim.fast._layout import Constants, Scratch, World
from swarmtag.sim.fast._motion import collide_range, resolve_begin, resolve_finish
from swarmtag.sim.fast._tick import draw, tick_begin, tick_end, tick_robots

__all__ = [
    "split_begin",
    "split_collide",
    "split_collide_begin",
    "split_copy",
    "split_draw",
    "split_finish",
    "split_index_robots",
    "split_robots",
    "thread_scratch",
]


def thread_scratch(x: Scratch) -> Scratch:
    """``x`` with query buffers of its own, for a second thread on the same runs."""
    return x._replace(
        gathered=np.zeros_like(x.gathered),
        near_carriers=np.zeros_like(x.near_carriers),
        near_blockers=np.zeros_like(x.near_blockers),
        near_robots=np.zeros_like(x.near_robots),
    )


@entry
def split_draw(
    r: int,
    motion: np.random.Generator,
    breakdown: np.random.Generator,
    radio: np.random.Generator,
    camera: np.random.Generator,
    k: Constants,
    x: Scratch,
) -> None:
    """Step 0: the random numbers of run ``r``'s next tick (see the module docs)."""
    draw(r, motion, breakdown, radio, camera, k, x)


@entry
def split_begin(r: int, t: int, robots: bool, w: World, k: Constants, x: Scratch) -> None:
    """Step 1 of tick ``t`` of run ``r`` (``robots``: with the robots' index)."""
    tick_begin(r, t, robots, w, k, x)


@entry
def split_index_robots(r: int, w: World, k: Constants, x: Scratch) -> None:
    """Step 1b: the robots' index, on another thread than the rest of step 1."""
    index_robots(r, w, k, x)


@entry
def split_robots(
    r: int,
    t: int,
    lo: int,
    hi: int,
    turns: np.ndarray,
    row: int,
    w: World,
    k: Constants,
    x: Scratch,
) -> None:
    """Step 2 for robots ``lo .. hi - 1``."""
    tick_robots(r, t, lo, hi, turns, row, w, k, x)


@entry
def split_collide_begin(r: int, copy: bool, w: World, k: Constants, x: Scratch) -> int:
    """Step 3: returns how many robots the first collision pass computes.

    ``copy``: copy the robots to their grid slots here, on one thread.
    """
    count: int = resolve_begin(r, copy, w, k, x)
    return count


@entry
def split_copy(r: int, lo: int, hi: int, x: Scratch) -> None:
    """Step 3b (with the robots' grid): robots ``lo .. hi - 1`` copied to their grid slots."""
    copy_to_slots(r, lo, hi, x)


@entry
def split_collide(r: int, lo: int, hi: int, w: World, k: Constants, x: Scratch) -> None:
    """Step 4 for the first pass's robots ``x.active[r, lo:hi]``."""
    collide_range(r, lo, hi, True, w, k, x)


@entry
def split_finish(r: int, t: int, count: int, w: World, k: Constants, x: Scratch) -> None:
    """Step 5: the rest of tick ``t``; the run's tick becomes ``t``."""
    resolve_finish(r, count, w, k, x)
    tick_end(r, t, w, k, x)
    w.run_tick[r] = t
