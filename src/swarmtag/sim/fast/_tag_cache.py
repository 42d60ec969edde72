"""A robot's tag cache in the compiled kernel: dense like the reference, or a short list.

Dense (``Constants.sparse_cache`` false): the ``WorldState`` arrays, one entry
per robot and carrier (``known_status``, ``known_urgency``, ``heard_tick``,
``blocked_until``), read and written as ``sim/world/sensing.py`` and ``sim/builtin/decide.py``
do.

Sparse (``sim.params.sparse_tag_cache``: split perception without sighting
memory or per-pair draws): a dense cache grows with robots times carriers,
and in a warehouse, whose carriers are orders that keep arriving, with the
run (a million robots could not hold it). Each robot instead keeps a list
of at most ``cache_capacity`` entries (``World.cache_*``, in no order): the
carriers it last heard ``AWAITING_PICKUP`` and its target. What is left out
cannot change what the robot does, which keeps the event logs the
reference's:

- a carrier is a candidate only if last heard ``AWAITING_PICKUP``; a carrier
  last heard otherwise acts as one never heard, so hearing another status
  drops its entry, except the target's, whose status decides abandonment.
  A tag's status only moves forward (AWAITING_PICKUP, PICKED_UP, then IDLE
  as it leaves; operator writes change urgency only), so a dropped
  cool-down can never matter again;
- a carrier leaves the floor once (lifted, then delivered and gone) and is
  never seen again, so entries of carriers off the floor can go
  (``_purge``, when the list is full), except the target's;
- the cool-down (``blocked_until``) only matters for a candidate, so it lives
  in the carrier's entry.

After a purge a list holds at most one entry per place a carrier can stand
on the floor (a warehouse's pick-up slots, the lab's carriers) and the
target: a capacity of places + 2 (``_layout.cache_bound``) never overflows.
A smaller one may: the kernel then stops the run (``FAILURE_CACHE_FULL``)
and the runner starts the batch again with twice the capacity, which gives
the same bytes. The tick in which each tag was last heard (``heard_tick``)
is not kept: nothing reads it.
"""

from __future__ import annotations

from typing import Final

from swarmtag.sim.fast._jit import inlined
from swarmtag.sim.fast._layout import Constants, World
from swarmtag.sim.fast._scratch import Scratch
from swarmtag.tag import TagStatus

__all__ = [
    "FAILURE_CACHE_FULL",
    "block",
    "hear",
    "known_blocked_until",
    "known_status",
    "known_urgency",
]

FAILURE_CACHE_FULL: Final = 3
"""``Scratch.failure`` of a run in which a robot's sparse tag cache overflowed."""


@inlined
def _find(r: int, n: int, c: int, w: World) -> int:
    """Where carrier ``c`` is in robot ``n``'s sparse list, -1 if absent."""
    for i in range(w.cache_count[r, n]):
        if w.cache_carrier[r, n, i] == c:
            return i
    return -1


@inlined
def known_status(r: int, n: int, c: int, w: World, k: Constants) -> int:
    """The status robot ``n`` last heard from carrier ``c``'s tag; -1 never (or forgotten)."""
    if not k.sparse_cache:
        status: int = w.known_status[r, n, c]
        return status
    i = _find(r, n, c, w)
    return w.cache_status[r, n, i] if i >= 0 else -1


@inlined
def known_urgency(r: int, n: int, c: int, w: World, k: Constants) -> int:
    """The urgency robot ``n`` last heard from carrier ``c``'s tag (0 if never)."""
    if not k.sparse_cache:
        urgency: int = w.known_urgency[r, n, c]
        return urgency
    i = _find(r, n, c, w)
    return w.cache_urgency[r, n, i] if i >= 0 else 0


@inlined
def known_blocked_until(r: int, n: int, c: int, w: World, k: Constants) -> int:
    """The first tick at which robot ``n`` may select carrier ``c`` again."""
    if not k.sparse_cache:
        until: int = w.blocked_until[r, n, c]
        return until
    i = _find(r, n, c, w)
    return w.cache_blocked[r, n, i] if i >= 0 else 0


@inlined
def block(r: int, n: int, c: int, until: int, w: World, k: Constants) -> None:
    """Robot ``n`` may not select carrier ``c``, its target, before tick ``until``.

    In a sparse list the target always has its entry (it was heard
    AWAITING_PICKUP to be selected, and is never dropped while the target).
    """
    if not k.sparse_cache:
        w.blocked_until[r, n, c] = until
        return
    i = _find(r, n, c, w)
    if i >= 0:
        w.cache_blocked[r, n, i] = until


@inlined
def _drop(r: int, n: int, i: int, w: World) -> None:
    """Remove entry ``i`` of robot ``n``'s sparse list (the last one takes its place)."""
    last = w.cache_count[r, n] - 1
    w.cache_carrier[r, n, i] = w.cache_carrier[r, n, last]
    w.cache_status[r, n, i] = w.cache_status[r, n, last]
    w.cache_urgency[r, n, i] = w.cache_urgency[r, n, last]
    w.cache_blocked[r, n, i] = w.cache_blocked[r, n, last]
    w.cache_count[r, n] = last


@inlined
def _purge(r: int, n: int, w: World) -> int:
    """Drop the entries of carriers off the floor (carried or gone) but the target's."""
    target = w.target[r, n]
    i = 0
    while i < w.cache_count[r, n]:
        c = w.cache_carrier[r, n, i]
        if c != target and not (w.present[r, c] and w.carried_by[r, c] < 0):
            _drop(r, n, i, w)
        else:
            i += 1
    count: int = w.cache_count[r, n]
    return count


@inlined
def hear(
    r: int, n: int, c: int, t: int, status: int, urgency: int, w: World, k: Constants, x: Scratch
) -> None:
    """Robot ``n`` hears carrier ``c``'s tag advertise ``status`` and ``urgency`` in tick ``t``."""
    if not k.sparse_cache:
        w.known_status[r, n, c] = status
        w.known_urgency[r, n, c] = urgency
        w.heard_tick[r, n, c] = t
        return
    i = _find(r, n, c, w)
    if i >= 0:
        if status == TagStatus.AWAITING_PICKUP or c == w.target[r, n]:
            w.cache_status[r, n, i] = status
            w.cache_urgency[r, n, i] = urgency
        else:
            _drop(r, n, i, w)
        return
    if status != TagStatus.AWAITING_PICKUP:
        return
    count = w.cache_count[r, n]
    if count == k.cache_capacity:
        count = _purge(r, n, w)
        if count == k.cache_capacity:
            x.failure[r] = FAILURE_CACHE_FULL
            return
    w.cache_carrier[r, n, count] = c
    w.cache_status[r, n, count] = status
    w.cache_urgency[r, n, count] = urgency
    w.cache_blocked[r, n, count] = 0
    w.cache_count[r, n] = count + 1
