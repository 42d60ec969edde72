"""One compiled tick of one run, and the loop that advances every run of a batch.

``tick_run`` is ``kernel.step`` for run ``r`` (the phases in the reference's
order, then the tick's events into the run's buffer). ``advance`` runs some
runs of the batch, each on its own until it ends, reaches ``until`` or its
event buffer could overflow; the caller empties the buffers and calls again.
It holds no GIL, so the caller runs groups of runs on several threads at
once: runs share no memory. Random numbers come from each run's own
generators, the very streams the reference draws (``RandomSource``), in the
same order; the numbers drawn outside the kernel (the walk's turns, the odometry's
numbers, the RSSI's error factors) come ready-made from the caller (``outside_row``).
"""

from __future__ import annotations

import math

import numpy as np

from swarmtag.sim.fast._collide import resolve_run
from swarmtag.sim.fast._decide import break_down_robots, decide_robots
from swarmtag.sim.fast._docking import (
    answer_lifts,
    arrive_run,
    carry_robots,
    deliver_run,
    dock_robots,
)
from swarmtag.sim.fast._draws import draw
from swarmtag.sim.fast._events import flush_slots, room_for_tick
from swarmtag.sim.fast._index import index_obstacles, index_robots
from swarmtag.sim.fast._jit import entry, glue, inlined, jit
from swarmtag.sim.fast._layout import Constants, World
from swarmtag.sim.fast._motion import move_robots, start_body
from swarmtag.sim.fast._orders import place_orders_run
from swarmtag.sim.fast._scratch import Scratch
from swarmtag.sim.fast._sense import sense_robots, tags_advertising

__all__ = ["advance", "outside_drawn", "outside_row", "start_call", "tick_run"]

ROBOT_BLOCK = 256
"""Robots a split run's thread takes through each phase in turn (``tick_robots``; 64 to
4,096 stepped 20,000 robots alike)."""


@inlined
def _end_of_tick(r: int, t: int, w: World, k: Constants) -> None:
    """Grow urgencies, record what the tags advertise, end the run (``kernel._end_of_tick``)."""
    slot = t % (k.status_delay + 1)
    remaining = False
    for c in range(k.carriers):
        w0 = w.w0[r, c]
        if not math.isnan(w0) and w.arrival_time[r, c] >= 0:
            grown = math.floor(9.0 * (w0 + t) / k.horizon)
            w.urgency[r, c] = min(9, grown)
        w.adv_status[r, slot, c] = w.status[r, c]
        w.adv_urgency[r, slot, c] = w.urgency[r, c]
        if w.present[r, c] or w.arrival_time[r, c] < 0:  # on the floor, or still to come
            remaining = True
    if w.ended_at[r] < 0 and (not remaining or t >= k.run_ticks):
        w.ended_at[r] = t


@inlined
def outside_drawn(k: Constants) -> bool:
    """Whether ticks have numbers drawn outside the kernel (turns, odometry, RSSI factors).

    Then ``outside[r, row, n]`` holds robot ``n``'s walk turn ``(cos, sin)``
    (a curved walk's turn per tick; zeros when the walk neither turns nor
    curves), in columns 2-3 its odometry stream's two Gaussian numbers
    (zeros without drift) and, from column 4, its RSSI error factor per
    carrier (with BLE-led search and shadowing); else ``outside`` has one
    row of zeros.
    """
    return (
        k.walk_turn_ticks > 0
        or k.walk_curve > 0
        or k.odometry_drift > 0
        or (k.radio_search and k.rssi_sigma > 0)
    )


@inlined
def outside_row(t: int, first: int, k: Constants) -> int:
    """The row of ``outside`` holding tick ``t``'s numbers (``first``: the first row's tick)."""
    return t - first if outside_drawn(k) else 0


@inlined
def start_call(r: int, x: Scratch) -> None:
    """A kernel call's first tick of run ``r`` builds afresh what the caller may have changed.

    The obstacle index (``Scratch.obstacles_current``) and the tags'
    advertising clocks (``Scratch.advert_tick``) are otherwise kept from tick
    to tick.
    """
    x.obstacles_current[r] = False
    x.advert_tick[r] = -1


@glue
def tick_run(
    r: int,
    t: int,
    outside: np.ndarray,
    row: int,
    streams: np.ndarray,
    w: World,
    k: Constants,
    x: Scratch,
) -> None:
    """Tick ``t`` of run ``r``: every phase of ``kernel.step`` but the operator writes.

    ``outside[r, row]`` are the tick's numbers drawn outside the kernel (``outside_row``).
    """
    draw(r, streams, k, x)
    tick_begin(r, t, True, w, k, x)
    robots = k.robots
    sense_robots(r, t, 0, robots, outside, row, w, k, x)
    break_down_robots(r, 0, robots, w, k, x)
    decide_robots(r, t, 0, robots, outside, row, w, k, x)
    move_robots(r, 0, robots, w, k, x)
    resolve_run(r, w, k, x)
    tick_end(r, t, w, k, x)


@inlined
def tick_begin(r: int, t: int, robots: bool, w: World, k: Constants, x: Scratch) -> None:
    """The robots' start, the run's index and advertising tags (after the tick's ``draw``).

    ``robots``: the index of the robots too (else the caller builds it,
    ``_index.index_robots``: it writes nothing the rest reads or writes).
    """
    for n in range(k.robots):
        x.before_mode[r, n] = w.mode[r, n]
        x.before_pos[r, n, 0] = w.robot_pos[r, n, 0]
        x.before_pos[r, n, 1] = w.robot_pos[r, n, 1]
    if not x.obstacles_current[r]:  # else unchanged since the last tick indexed them
        index_obstacles(r, w, k, x)
    if robots:
        index_robots(r, w, k, x)
    if k.split:
        tags_advertising(r, t, w, k, x)


@glue
def tick_robots(
    r: int,
    t: int,
    lo: int,
    hi: int,
    outside: np.ndarray,
    row: int,
    w: World,
    k: Constants,
    x: Scratch,
) -> None:
    """Sense, break down, decide and move robots ``lo .. hi - 1``, a block at a time.

    Each robot reads the run's state as the tick began and writes only its
    own entries (and its event slots), so ranges of robots may run at once
    on several threads, each with its own query buffers (``Scratch.near_*``),
    and a block of robots may go through each phase in turn (tight loops:
    0.52 -> 0.42 ms a thread at 20,000 robots against one robot after another;
    the blocks keep a million robots' entries in cache between the phases).
    Each also sets its body for the collisions (``resolve_begin(split=True)``).
    """
    for block in range(lo, hi, ROBOT_BLOCK):
        end = min(block + ROBOT_BLOCK, hi)
        sense_robots(r, t, block, end, outside, row, w, k, x)
        break_down_robots(r, block, end, w, k, x)
        decide_robots(r, t, block, end, outside, row, w, k, x)
        move_robots(r, block, end, w, k, x)
        for n in range(block, end):
            start_body(r, n, w, k, x)


@inlined
def tick_end(r: int, t: int, w: World, k: Constants, x: Scratch) -> None:
    """Every phase after the collisions: docking, lifts, deliveries, end of tick, orders."""
    tick_settle(r, t, w, k, x)
    tick_finish(r, t, w, k, x)


@inlined
def tick_settle(r: int, t: int, w: World, k: Constants, x: Scratch) -> None:
    """Arrivals and docking: after them no robot moves again this tick (``tick_finish``)."""
    arrive_run(r, 4 * t, w, k, x)
    dock_robots(r, 0, k.robots, w, x)


@inlined
def tick_finish(r: int, t: int, w: World, k: Constants, x: Scratch) -> None:
    """Lifts, deliveries, end of tick, orders, events: robots' positions read, never written."""
    robots = k.robots
    lifted = answer_lifts(r, t, 4 * t + 2, w, k, x)
    carry_robots(r, 0, robots, w, k, x)
    deliver_run(r, t, lifted, w, k, x)
    _end_of_tick(r, t, w, k)
    place_orders_run(r, t, w, k, x)
    flush_slots(r, t, robots, x)


@jit
def _run_to(
    r: int,
    until: int,
    outside: np.ndarray,
    outside_from: int,
    streams: np.ndarray,
    w: World,
    k: Constants,
    x: Scratch,
) -> None:
    """Run ``r`` tick by tick to ``until``, its end, or a full event buffer."""
    start_call(r, x)
    while w.ended_at[r] < 0 and w.run_tick[r] < until and x.failure[r] == 0:
        if not room_for_tick(r, k.robots + k.pickup_slots.shape[0], x):
            return
        t = w.run_tick[r] + 1
        row = outside_row(t, outside_from, k)
        tick_run(r, t, outside, row, streams, w, k, x)
        w.run_tick[r] = t


@entry
def advance(
    rows: np.ndarray,
    until: int,
    outside: np.ndarray,
    outside_from: int,
    streams: np.ndarray,
    w: World,
    k: Constants,
    x: Scratch,
) -> None:
    """Advance the runs ``rows`` to tick ``until`` (or their end, or until a buffer is full).

    ``outside[r, t - outside_from]`` holds run ``r``'s numbers of tick ``t`` drawn
    outside the kernel (``outside_row``); ``streams[r]`` are run
    ``r``'s generator states (``_draws.STREAMS``' rows, ``_pcg``), advanced in place.
    """
    for i in range(rows.shape[0]):
        r = rows[i]
        _run_to(r, until, outside, outside_from, streams, w, k, x)
