"""Phase 2 of a tick, decide: breakdowns, pursuit checks, selection, walk directions.

In this order, for every robot at once:

1. a robot whose breakdown number fires breaks down for good (a carrier it
   holds stays PICKED_UP with it: stuck);
2. a pursuing robot (PREDOCK, DOCK, CENTRE) abandons when the status it last
   heard from its target is not AWAITING_PICKUP, else times out when the
   pursuit has lasted ``timeout_ticks`` (that carrier is then barred to it
   for ``cooldown_ticks``); either way it returns to random walk;
3. a robot that was walking at the start of the tick selects, with the
   policy's ``select``, among carriers it detects, last heard as
   AWAITING_PICKUP, not cooling down for it and with a free predock face;
   it will dock at the free face whose predock point is nearest to it;
4. a walking robot that touched something last tick, or has just returned
   to walking, takes this tick's random direction, reversed if it points
   into what it touched (negative dot product with the contact push);
5. a loaded robot stuck for ``stuck_ticks`` starts a sidestep of
   ``sidestep_ticks`` along this tick's sidestep direction (reversed alike).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from swarmtag.policy import select
from swarmtag.sim._index import PURSUIT_MODES, at_robots, grid, in_modes, is_loaded, own, to_walk
from swarmtag.sim.events import EventKind, TickEvents
from swarmtag.sim.geometry import Float
from swarmtag.sim.params import Params
from swarmtag.sim.predock import nearest_free_face
from swarmtag.sim.randomness import TickInputs
from swarmtag.sim.sense import Senses
from swarmtag.sim.state import Mode, WorldState
from swarmtag.tag import TagStatus

__all__ = ["away_from", "decide"]

_AWAITING = int(TagStatus.AWAITING_PICKUP)


def away_from(direction: Float, push: Float) -> Float:
    """``direction`` reversed where it points against ``push`` (negative dot product).

    >>> away_from(np.array([[1.0, 0.0]]), np.array([[-0.01, 0.0]]))
    array([[-1., -0.]])
    """
    dot = direction[..., 0] * push[..., 0] + direction[..., 1] * push[..., 1]
    return np.where((dot < 0)[..., None], -direction, direction)


def _breakdowns(s: WorldState, inputs: TickInputs, events: TickEvents) -> None:
    broken = inputs.breakdown & (s.mode != Mode.BROKEN)
    if not broken.any():
        return
    loaded = is_loaded(s.mode, s.target)
    events.add(
        EventKind.BREAKDOWN, broken, np.where(loaded, s.target, -1), np.full(broken.shape, np.nan)
    )
    s.target[broken & ~loaded] = -1
    s.face[broken] = -1
    s.timer[broken] = 0
    s.mode[broken] = Mode.BROKEN


def _pursuit_checks(s: WorldState, params: Params, t: int, events: TickEvents) -> None:
    pursuing = in_modes(s.mode, PURSUIT_MODES)
    if not pursuing.any():
        return
    heard = own(s.known_status, s.target)
    abandon = pursuing & (heard != _AWAITING)
    timeout = pursuing & ~abandon & (t - s.pursuit_start >= params.timeout_ticks)
    events.add(EventKind.ABANDON, abandon, s.target, heard.astype(np.float64))
    events.add(EventKind.TIMEOUT, timeout, s.target, np.full(timeout.shape, np.nan))
    runs, robots = np.nonzero(timeout)
    s.blocked_until[runs, robots, s.target[runs, robots]] = t + params.cooldown_ticks
    to_walk(s, abandon | timeout)


def _selection(
    s: WorldState,
    *,
    senses: Senses,
    walkers: NDArray[np.bool_],
    params: Params,
    t: int,
    events: TickEvents,
) -> None:
    if not walkers.any():
        return
    available = (
        walkers[..., None]
        & senses.in_range
        & (s.known_status == _AWAITING)
        & (s.blocked_until <= t)
        & np.any(s.free_face, axis=-1)[:, None, :]
    )
    if not available.any():
        return
    choice = select(
        params.policy,
        urgency=s.known_urgency,
        distance=senses.distance,
        marker=params.markers,
        available=available,
    ).astype(np.int64)
    chosen = choice >= 0
    rows, robots = grid(*choice.shape)
    face = nearest_free_face(
        s.robot_pos,
        at_robots(s.carrier_pos, choice),
        at_robots(s.free_face, choice),
        params.predock_offset,
    )
    heard = s.known_urgency[rows, robots, np.maximum(choice, 0)].astype(np.float64)
    events.add(EventKind.SELECT, chosen, choice, heard)
    s.mode[chosen] = Mode.PREDOCK
    s.target[chosen] = choice[chosen]
    s.face[chosen] = face[chosen]
    s.pursuit_start[chosen] = t


def decide(
    before: WorldState,
    s: WorldState,
    *,
    senses: Senses,
    inputs: TickInputs,
    params: Params,
    t: int,
    events: TickEvents,
) -> None:
    """Apply the decisions of tick ``t`` to ``s`` in place (``before``: the state at tick start)."""
    _breakdowns(s, inputs, events)
    _pursuit_checks(s, params, t, events)
    walkers = (before.mode == Mode.WALK) & (s.mode == Mode.WALK)
    _selection(s, senses=senses, walkers=walkers, params=params, t=t, events=events)

    bumped = (s.contact != 0).any(axis=-1)
    fresh = (s.mode == Mode.WALK) & (s.redirect | bumped)
    if fresh.any():
        np.copyto(s.walk, away_from(inputs.walk, s.contact), where=fresh[..., None])
        s.redirect[fresh] = False

    unstick = (s.mode == Mode.TRANSPORT) & (s.stuck >= params.stuck_ticks) & (s.sidestep == 0)
    if unstick.any():
        np.copyto(s.sidestep_dir, away_from(inputs.sidestep, s.contact), where=unstick[..., None])
        s.sidestep[unstick] = params.sidestep_ticks
        s.stuck[unstick] = 0
