"""Phase 5 of a tick: dock, lift and release (SPEC §3.2, §4.2).

In this order, from the positions after collisions:

1. timers of robots already centring, lifting or releasing count down;
2. a robot in PREDOCK within ``arrival_tolerance`` of its predock point and
   facing the carrier drives in (DOCK), unless another robot is already
   docking, centring or lifting under that carrier (it waits where it is;
   of several arriving in the same tick the smallest id goes in); a robot
   in DOCK within that distance
   of the carrier centre is snapped onto it and centres for ``dock_ticks``
   (CENTRE);
3. a robot whose centring is over lifts: the tag accepts the robot's write
   AWAITING_PICKUP -> PICKED_UP only from AWAITING_PICKUP (the lifecycle's
   robot transitions); of several robots lifting one carrier in the same
   tick the smallest id wins, the others go back to walking
   (``lift_refused``); the winner holds it for ``lift_ticks`` (LIFT);
4. a robot whose lift is over heads for the drop-off area (TRANSPORT), to the
   point at the area's middle x and its own y (kept clear of the walls);
5. a loaded robot whose carrier lies wholly inside the drop-off area lowers
   it for ``release_ticks`` (RELEASE), then writes PICKED_UP -> IDLE: the
   carrier is delivered and leaves the arena, and the robot walks again.

Predock faces are recomputed for runs in which a carrier was lifted (one
obstacle fewer).
"""

from __future__ import annotations

from typing import Final

import numpy as np
from numpy.typing import NDArray

from swarmtag.errors import SimulationError
from swarmtag.sim._index import at_robots, in_modes, to_walk
from swarmtag.sim.events import EventKind, TickEvents
from swarmtag.sim.geometry import FACE_NORMALS, length
from swarmtag.sim.params import Params
from swarmtag.sim.predock import free_faces
from swarmtag.sim.state import Mode, WorldState
from swarmtag.tag import ROBOT_TRANSITIONS, TagStatus

__all__ = ["ROBOT_WRITE_ALLOWED", "handle"]


def _transition_table() -> NDArray[np.bool_]:
    table = np.zeros((len(TagStatus), len(TagStatus)), dtype=bool)
    for before, after in ROBOT_TRANSITIONS:
        table[int(before), int(after)] = True
    table.flags.writeable = False
    return table


ROBOT_WRITE_ALLOWED: Final = _transition_table()
"""``[from, to]``: may a robot write this status change (``tag.ROBOT_TRANSITIONS`` as a table)."""


_DOCK_TAKEN: Final = (Mode.DOCK, Mode.CENTRE, Mode.LIFT)


def _dock_free(s: WorldState, arriving: NDArray[np.bool_]) -> NDArray[np.bool_]:
    """Which arriving robots may drive in: nobody under their carrier, and no smaller id arriving.

    Only one robot fits under a carrier; a robot at its predock point sees one
    already there with its range sensors and waits (it abandons when it hears
    the lift, or times out).
    """
    runs, robots = s.mode.shape
    target = np.maximum(s.target, 0)
    inside = in_modes(s.mode, _DOCK_TAKEN)
    taken = np.zeros((runs, s.carrier_pos.shape[1]), dtype=bool)
    rows, ids = np.nonzero(inside)
    taken[rows, target[rows, ids]] = True
    free = arriving & ~taken[np.arange(runs)[:, None], target]
    same = free[:, :, None] & free[:, None, :] & (target[:, :, None] == target[:, None, :])
    smaller = np.tri(robots, k=-1, dtype=bool)  # [i, j]: j < i
    first: NDArray[np.bool_] = free & ~(same & smaller).any(axis=2)
    return first


def _arrivals(s: WorldState, params: Params) -> None:
    centre = at_robots(s.carrier_pos, s.target)
    normal = FACE_NORMALS[np.maximum(s.face, 0)]
    predock = centre + normal * params.predock_offset
    facing = (s.heading == -normal).all(axis=-1)
    at_predock = (
        (s.mode == Mode.PREDOCK)
        & (length(s.robot_pos - predock) <= params.arrival_tolerance)
        & facing
    )
    at_predock &= _dock_free(s, at_predock)
    at_centre = (s.mode == Mode.DOCK) & (length(s.robot_pos - centre) <= params.arrival_tolerance)
    s.mode[at_predock] = Mode.DOCK
    s.ghost[at_predock] = s.target[at_predock]
    s.mode[at_centre] = Mode.CENTRE
    s.timer[at_centre] = params.dock_ticks
    np.copyto(s.robot_pos, centre, where=at_centre[..., None])


def _lifts(s: WorldState, params: Params, t: int, events: TickEvents) -> NDArray[np.bool_]:
    """Lift where centring is over; return the runs in which a carrier was lifted."""
    want = (s.mode == Mode.CENTRE) & (s.timer == 0)
    if not want.any():
        return np.zeros(s.mode.shape[0], dtype=bool)
    status = at_robots(s.status, s.target).astype(np.int64)
    claim = (
        want
        & ROBOT_WRITE_ALLOWED[status, int(TagStatus.PICKED_UP)]
        & (at_robots(s.carried_by, s.target) < 0)
        & at_robots(s.present, s.target)
    )
    robots = s.mode.shape[1]
    index = np.arange(robots)
    rival = (
        claim[:, None, :]
        & (s.target[:, None, :] == s.target[:, :, None])
        & (index[None, :] < index[:, None])[None, :, :]
    ).any(axis=-1)  # a smaller-id robot claims the same carrier
    win = claim & ~rival
    lose = want & ~win
    events.add(EventKind.LIFT_REFUSED, lose, s.target, status.astype(np.float64))
    to_walk(s, lose)

    runs, holders = np.nonzero(win)
    carriers = s.target[runs, holders]
    s.status[runs, carriers] = TagStatus.PICKED_UP
    s.carried_by[runs, carriers] = holders
    s.pickup_time[runs, carriers] = t
    events.add(EventKind.LIFT, win, s.target, at_robots(s.urgency, s.target).astype(np.float64))
    s.mode[win] = Mode.LIFT
    s.timer[win] = params.lift_ticks
    lifted: NDArray[np.bool_] = win.any(axis=1)
    return lifted


def _deliveries(s: WorldState, params: Params, t: int, events: TickEvents) -> None:
    inside = s.robot_pos[..., 0] - params.carrier_half >= params.dropoff_left
    arrive = (s.mode == Mode.TRANSPORT) & inside
    s.mode[arrive] = Mode.RELEASE
    s.timer[arrive] = params.release_ticks

    done = (s.mode == Mode.RELEASE) & (s.timer == 0)
    if not done.any():
        return
    status = at_robots(s.status, s.target).astype(np.int64)
    if not ROBOT_WRITE_ALLOWED[status[done], int(TagStatus.IDLE)].all():  # pragma: no cover
        msg = f"tick {t}: a robot released a carrier whose tag is not PICKED_UP"
        raise SimulationError(msg)
    runs, robots = np.nonzero(done)
    carriers = s.target[runs, robots]
    s.status[runs, carriers] = TagStatus.IDLE
    s.present[runs, carriers] = False
    s.carried_by[runs, carriers] = -1
    s.delivery_time[runs, carriers] = t
    s.deliverer[runs, carriers] = robots
    s.delivery_urgency[runs, carriers] = s.urgency[runs, carriers]
    events.add(EventKind.DELIVER, done, s.target, at_robots(s.urgency, s.target).astype(np.float64))
    to_walk(s, done)


def handle(s: WorldState, params: Params, t: int, events: TickEvents) -> None:
    """Apply the dock, lift and release phase of tick ``t`` to ``s`` in place."""
    timed = in_modes(s.mode, (Mode.CENTRE, Mode.LIFT, Mode.RELEASE)) & (s.timer > 0)
    s.timer[timed] -= 1
    _arrivals(s, params)
    lifted = _lifts(s, params, t, events)

    raised = (s.mode == Mode.LIFT) & (s.timer == 0)
    if raised.any():
        s.mode[raised] = Mode.TRANSPORT
        s.ghost[raised] = -1
        s.stuck[raised] = 0
        s.sidestep[raised] = 0
        y = np.clip(s.robot_pos[..., 1], params.carrier_half, params.arena - params.carrier_half)
        goal = np.stack((np.full(y.shape, params.transport_x), y), axis=-1)
        np.copyto(s.goal, goal, where=raised[..., None])

    _deliveries(s, params, t, events)
    if lifted.any():
        rows = np.flatnonzero(lifted)
        obstacle = s.present[rows] & (s.carried_by[rows] < 0)
        s.free_face[rows] = free_faces(s.carrier_pos[rows], obstacle, params)
