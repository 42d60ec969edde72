"""The built-in controller's steps after the move: arriving, docking, lifting, releasing.

``arrive`` (after the move and the collisions), in this order:

1. a loaded robot driving to the drop-off area (not sidestepping) that
   moved less than a quarter of its step counts a stuck tick;
2. timers of robots centring, lifting or releasing count down;
3. a robot in PREDOCK within ``arrival_tolerance`` of its predock point and
   facing the carrier drives in (DOCK), unless another robot is already
   docking, centring or lifting under that carrier (it waits where it is;
   of several arriving in the same tick the smallest id goes in); a robot
   in DOCK within that distance of the carrier centre centres for
   ``dock_ticks`` (CENTRE);
4. a robot whose centring is over asks to lift: it writes PICKED_UP to the
   carrier's tag (the world answers).

``carry`` (after the tags' answers):

1. a robot whose lift write was refused returns to random walk; one whose
   write was accepted holds the carrier for ``lift_ticks`` (LIFT);
2. a robot whose lift is up heads for the drop-off area (TRANSPORT), to the
   point at the area's middle x and its own y (kept clear of the walls); in
   a warehouse along its path to the carrier's destination area (the move
   sets each tick's waypoint);
3. a loaded robot whose carrier lies wholly inside its drop-off area lowers
   it for ``release_ticks`` (RELEASE), then writes IDLE (the world delivers
   the carrier) and walks again.
"""

from __future__ import annotations

from typing import Final

import numpy as np
from numpy.typing import NDArray

from swarmtag.sim.control.interface import Arrivals, Carrying, LiftAnswers
from swarmtag.sim.control.rules import STUCK_PROGRESS
from swarmtag.sim.model.geometry import FACE_NORMALS, length
from swarmtag.sim.model.indexing import at_robots, in_dropoff, in_modes, to_walk
from swarmtag.sim.model.params import Params
from swarmtag.sim.model.state import Mode, WorldState
from swarmtag.sim.world.broad_phase import first_claims

__all__ = ["arrive", "carry"]

_DOCK_TAKEN: Final = (Mode.DOCK, Mode.CENTRE, Mode.LIFT)


def _dock_free(s: WorldState, arriving: NDArray[np.bool_]) -> NDArray[np.bool_]:
    """Which arriving robots may drive in: nobody under their carrier, and no smaller id arriving.

    Only one robot fits under a carrier; a robot at its predock point sees one
    already there with its range sensors and waits (it abandons when it hears
    the lift, or times out).
    """
    runs = s.mode.shape[0]
    target = np.maximum(s.target, 0)
    inside = in_modes(s.mode, _DOCK_TAKEN)
    taken = np.zeros((runs, s.carrier_pos.shape[1]), dtype=bool)
    rows, ids = np.nonzero(inside)
    taken[rows, target[rows, ids]] = True
    free = arriving & ~taken[np.arange(runs)[:, None], target]
    return first_claims(free, target, s.carrier_pos.shape[1])


def arrive(before: WorldState, s: WorldState, *, params: Params, t: int) -> Arrivals:
    """The ``arrive`` step of tick ``t``: changes ``s`` in place, returns the requests."""
    transporting = (s.mode == int(Mode.TRANSPORT)) & (s.sidestep == 0)
    slow = length(s.robot_pos - before.robot_pos) < STUCK_PROGRESS * s.speed
    s.stuck[:] = np.where(transporting & slow, s.stuck + 1, 0)

    timed = in_modes(s.mode, (Mode.CENTRE, Mode.LIFT, Mode.RELEASE)) & (s.timer > 0)
    s.timer[timed] -= 1

    centre = at_robots(s.carrier_pos, s.target)
    normal = FACE_NORMALS[np.maximum(s.face, 0)]
    predock = centre + normal * params.predock_offset
    facing = (s.heading == -normal).all(axis=-1)
    at_predock = (
        (s.mode == int(Mode.PREDOCK))
        & (length(s.robot_pos - predock) <= params.arrival_tolerance)
        & facing
    )
    if at_predock.any():  # most ticks nobody arrives: nobody to check
        at_predock &= _dock_free(s, at_predock)
    at_centre = (s.mode == int(Mode.DOCK)) & (
        length(s.robot_pos - centre) <= params.arrival_tolerance
    )
    s.mode[at_predock] = Mode.DOCK
    s.mode[at_centre] = Mode.CENTRE
    s.timer[at_centre] = params.dock_ticks

    lift = (s.mode == int(Mode.CENTRE)) & (s.timer == 0)
    return Arrivals(drive_in=at_predock, centred=at_centre, lift=np.where(lift, s.target, -1))


def carry(s: WorldState, answers: LiftAnswers, *, params: Params, t: int) -> Carrying:
    """The ``carry`` step of tick ``t``: changes ``s`` in place, returns the requests."""
    to_walk(s, answers.refused)
    s.mode[answers.accepted] = Mode.LIFT
    s.timer[answers.accepted] = params.lift_ticks

    raised = (s.mode == int(Mode.LIFT)) & (s.timer == 0)
    if raised.any():
        s.mode[raised] = Mode.TRANSPORT
        s.stuck[raised] = 0
        s.sidestep[raised] = 0
        if params.floor is None:
            high = params.arena - params.carrier_half
            y = np.clip(s.robot_pos[..., 1], params.carrier_half, high)
            goal = np.stack((np.full(y.shape, params.transport_x), y), axis=-1)
            np.copyto(s.goal, goal, where=raised[..., None])

    arriving = (s.mode == int(Mode.TRANSPORT)) & in_dropoff(s, params, s.target)
    s.mode[arriving] = Mode.RELEASE
    s.timer[arriving] = params.release_ticks

    done = (s.mode == int(Mode.RELEASE)) & (s.timer == 0)
    lower = np.where(done, s.target, -1)
    to_walk(s, done)
    return Carrying(raised=raised, lower=lower)
