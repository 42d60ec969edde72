"""The world's side of a tick around the controller: breakdowns, docking physics, the tags.

- ``break_down`` (before the controller decides): a robot whose breakdown
  number fires breaks down for good; a carrier it holds stays PICKED_UP
  with it (stuck). The world takes the robot from its controller.
- ``dock`` (after ``arrive``): a robot that drives in may overlap its
  carrier; a robot that starts centring stands on the carrier's centre.
- ``answer_lifts``: each tag answers the robots' lift writes: it accepts
  AWAITING_PICKUP -> PICKED_UP only from AWAITING_PICKUP
  (``tag.ROBOT_TRANSITIONS`` as a table), and of several robots writing to
  one carrier in the same tick the smallest id wins. The lift itself only
  raises a carrier the robot stands centred under (it drove in, and is on
  the centre): a write from anywhere else is refused too.
- ``deliver`` (after ``carry``): a lifted robot no longer overlaps anything
  but its load; a carrier set down in the drop-off area and written IDLE is
  delivered and leaves the arena (the model has no other place to set a
  carrier down: a controller that lowers one elsewhere, or one it does not
  hold, is a ``SimulationError``). Predock faces are recomputed in runs in
  which a carrier was lifted (one obstacle fewer).
"""

from __future__ import annotations

from typing import Final

import numpy as np
from numpy.typing import NDArray

from swarmtag.errors import SimulationError
from swarmtag.sim.control.interface import Arrivals, Carrying, LiftAnswers
from swarmtag.sim.model.events import EventKind, TickEvents
from swarmtag.sim.model.geometry import length
from swarmtag.sim.model.indexing import at_robots, in_dropoff, is_loaded
from swarmtag.sim.model.params import Params
from swarmtag.sim.model.randomness import TickInputs
from swarmtag.sim.model.state import Int, Mode, WorldState
from swarmtag.sim.world.broad_phase import first_claims
from swarmtag.sim.world.predock import free_faces
from swarmtag.tag import ROBOT_TRANSITIONS, TagStatus

__all__ = ["ROBOT_WRITE_ALLOWED", "answer_lifts", "break_down", "deliver", "dock"]


def _transition_table() -> NDArray[np.bool_]:
    table = np.zeros((len(TagStatus), len(TagStatus)), dtype=bool)
    for before, after in ROBOT_TRANSITIONS:
        table[int(before), int(after)] = True
    table.flags.writeable = False
    return table


ROBOT_WRITE_ALLOWED: Final = _transition_table()
"""``[from, to]``: may a robot write this status change (``tag.ROBOT_TRANSITIONS`` as a table)."""


def break_down(s: WorldState, inputs: TickInputs, events: TickEvents) -> None:
    """Robots whose breakdown number fired this tick break down for good (in place)."""
    broken = inputs.breakdown & (s.mode != int(Mode.BROKEN))
    if not broken.any():
        return
    loaded = is_loaded(s.mode, s.target)
    events.add(
        EventKind.BREAKDOWN, broken, np.where(loaded, s.target, -1), np.full(broken.shape, np.nan)
    )
    s.target[broken & ~loaded] = -1
    s.face[broken] = -1
    s.mode[broken] = Mode.BROKEN


def _under(s: WorldState, carrier: Int, params: Params) -> NDArray[np.bool_]:
    """Robots standing centred under ``carrier`` (R, N): let in, and on its centre."""
    near = length(s.robot_pos - at_robots(s.carrier_pos, carrier))
    centred: NDArray[np.bool_] = (s.ghost == carrier) & (near <= params.arrival_tolerance)
    return centred


def dock(s: WorldState, arrivals: Arrivals) -> None:
    """Let robots that drive in overlap their carrier; put robots that centre on its centre."""
    s.ghost[arrivals.drive_in] = s.target[arrivals.drive_in]
    centre = at_robots(s.carrier_pos, s.target)
    np.copyto(s.robot_pos, centre, where=arrivals.centred[..., None])


def answer_lifts(
    s: WorldState, lift: Int, *, params: Params, t: int, events: TickEvents
) -> LiftAnswers:
    """The tags' answers to the lift writes ``lift`` (R, N) (carrier, -1 none), applied in place."""
    want = lift >= 0
    if not want.any():
        return LiftAnswers(accepted=want, refused=want.copy())
    status = at_robots(s.status, lift).astype(np.int64)
    claim = (
        want
        & ROBOT_WRITE_ALLOWED[status, int(TagStatus.PICKED_UP)]
        & (at_robots(s.carried_by, lift) < 0)
        & at_robots(s.present, lift)
        & _under(s, lift, params)
    )
    win = first_claims(claim, lift, s.carrier_pos.shape[1])  # a smaller id claiming it wins
    lose = want & ~win
    events.add(EventKind.LIFT_REFUSED, lose, lift, status.astype(np.float64))
    runs, holders = np.nonzero(win)
    carriers = lift[runs, holders]
    s.status[runs, carriers] = TagStatus.PICKED_UP
    s.carried_by[runs, carriers] = holders
    s.pickup_time[runs, carriers] = t
    events.add(EventKind.LIFT, win, lift, at_robots(s.urgency, lift).astype(np.float64))
    return LiftAnswers(accepted=win, refused=lose)


def deliver(
    s: WorldState,
    carrying: Carrying,
    *,
    answers: LiftAnswers,
    params: Params,
    t: int,
    events: TickEvents,
) -> None:
    """Apply the ``carry`` requests: drive-offs, set-downs and IDLE writes (in place)."""
    s.ghost[carrying.raised] = -1
    done = carrying.lower >= 0
    if done.any():
        status = at_robots(s.status, carrying.lower).astype(np.int64)
        if not ROBOT_WRITE_ALLOWED[status[done], int(TagStatus.IDLE)].all():
            msg = f"tick {t}: a robot released a carrier whose tag is not PICKED_UP"
            raise SimulationError(msg)
        holder = at_robots(s.carried_by, carrying.lower)
        inside = in_dropoff(s, params, carrying.lower)
        robots = np.arange(s.mode.shape[1])[None, :]
        if not ((holder == robots) & inside)[done].all():
            msg = (
                f"tick {t}: a robot lowered a carrier it does not hold, or outside the "
                "drop-off area (the model delivers only into the drop-off area)"
            )
            raise SimulationError(msg)
        runs, robots = np.nonzero(done)
        carriers = carrying.lower[runs, robots]
        s.status[runs, carriers] = TagStatus.IDLE
        s.present[runs, carriers] = False
        s.carried_by[runs, carriers] = -1
        s.delivery_time[runs, carriers] = t
        s.deliverer[runs, carriers] = robots
        s.delivery_urgency[runs, carriers] = s.urgency[runs, carriers]
        events.add(
            EventKind.DELIVER,
            done,
            carrying.lower,
            at_robots(s.urgency, carrying.lower).astype(np.float64),
        )
    lifted = answers.accepted.any(axis=1)
    if lifted.any():
        rows = np.flatnonzero(lifted)
        obstacle = s.present[rows] & (s.carried_by[rows] < 0)
        s.free_face[rows] = free_faces(s.carrier_pos[rows], obstacle, params)
