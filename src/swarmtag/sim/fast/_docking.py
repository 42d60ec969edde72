"""After the move, compiled: the ``docking`` steps and ``world.dock``/``answer_lifts``/``deliver``.

The controller's steps (``arrive_run``, ``carry_robots``) and the world's
(``dock_robots``, ``answer_lifts``, ``deliver_run``) in the reference's
order. Where robots compete (one robot fits under a carrier; one robot lifts
it) the smallest id wins, found in one pass in id order with a per-carrier
mark. ``free_faces_run`` is ``predock.free_faces`` for one run.
"""

from __future__ import annotations

from swarmtag.sim.control.rules import STUCK_PROGRESS
from swarmtag.sim.fast._decide import to_walk
from swarmtag.sim.fast._events import emit
from swarmtag.sim.fast._floor import clear_of_shelves, in_dropoff
from swarmtag.sim.fast._geometry import FACE_X, FACE_Y, contact, maximum, minimum, norm
from swarmtag.sim.fast._grid import near
from swarmtag.sim.fast._index import index_obstacles
from swarmtag.sim.fast._jit import inlined
from swarmtag.sim.fast._layout import Constants, World
from swarmtag.sim.fast._scratch import Scratch
from swarmtag.sim.model.events import EventKind
from swarmtag.sim.model.state import Mode
from swarmtag.tag import TagStatus

__all__ = [
    "FAILURE_LOWERED",
    "FAILURE_NOT_PICKED_UP",
    "answer_lifts",
    "arrive_clocks",
    "arrive_drive_in",
    "arrive_requests",
    "arrive_run",
    "carry_robots",
    "deliver_run",
    "dock_robots",
    "free_faces_run",
]


FAILURE_NOT_PICKED_UP = 1
"""``Scratch.failure``: a robot released a carrier whose tag is not PICKED_UP."""
FAILURE_LOWERED = 2
"""``Scratch.failure``: a robot lowered a carrier it does not hold, or outside the drop-off area."""


@inlined
def arrive_run(r: int, stamp: int, w: World, k: Constants, x: Scratch) -> None:
    """The ``arrive`` step: stuck ticks, timers, arrivals, lift requests (``docking.arrive``).

    ``stamp`` marks carriers taken under this tick (``Scratch.carrier_mark``).
    """
    arrive_clocks(r, 0, k.robots, stamp, w, k, x)
    arrive_drive_in(r, stamp, w, k, x)
    arrive_requests(r, 0, k.robots, w, k, x)


@inlined
def arrive_clocks(r: int, lo: int, hi: int, stamp: int, w: World, k: Constants, x: Scratch) -> None:
    """Stuck ticks and timers of robots ``lo .. hi - 1``; the carriers they dock at, marked.

    Ranges may run at once on several threads: a robot writes its own
    entries, and a carrier's mark only ever gets ``stamp`` here.
    """
    for n in range(lo, hi):
        mode = w.mode[r, n]
        moved = norm(
            w.robot_pos[r, n, 0] - x.before_pos[r, n, 0],
            w.robot_pos[r, n, 1] - x.before_pos[r, n, 1],
        )
        if (
            mode == Mode.TRANSPORT
            and w.sidestep[r, n] == 0
            and moved < STUCK_PROGRESS * w.speed[r, n]
        ):
            w.stuck[r, n] += 1
        else:
            w.stuck[r, n] = 0
        if mode in (Mode.CENTRE, Mode.LIFT, Mode.RELEASE) and w.timer[r, n] > 0:
            w.timer[r, n] -= 1
        if mode in (Mode.DOCK, Mode.CENTRE, Mode.LIFT):
            x.carrier_mark[r, max(w.target[r, n], 0)] = stamp


@inlined
def arrive_drive_in(r: int, stamp: int, w: World, k: Constants, x: Scratch) -> None:
    """Who drives in or is centred: after every range of ``arrive_clocks``, on one thread.

    At the predock point, facing the carrier, nobody under it, smallest id first.
    """
    for n in range(k.robots):
        x.drive_in[r, n] = False
        x.centred[r, n] = False
        mode = w.mode[r, n]
        if mode not in (Mode.PREDOCK, Mode.DOCK):
            continue
        target = max(w.target[r, n], 0)
        cx = w.carrier_pos[r, target, 0]
        cy = w.carrier_pos[r, target, 1]
        rx = w.robot_pos[r, n, 0]
        ry = w.robot_pos[r, n, 1]
        if mode == Mode.DOCK:
            x.centred[r, n] = norm(rx - cx, ry - cy) <= k.arrival_tolerance
            continue
        face = max(w.face[r, n], 0)
        nx = FACE_X[face]
        ny = FACE_Y[face]
        px = cx + nx * k.predock_offset
        py = cy + ny * k.predock_offset
        facing = w.heading[r, n, 0] == -nx and w.heading[r, n, 1] == -ny
        if (
            facing
            and norm(rx - px, ry - py) <= k.arrival_tolerance
            and x.carrier_mark[r, target] != stamp
            and x.carrier_mark[r, target] != stamp + 1
        ):
            x.drive_in[r, n] = True
            x.carrier_mark[r, target] = stamp + 1  # later ids arriving at it wait


@inlined
def arrive_requests(r: int, lo: int, hi: int, w: World, k: Constants, x: Scratch) -> None:
    """Robots ``lo .. hi - 1`` dock, centre or ask to lift (after ``arrive_drive_in``).

    Each writes its own entries: ranges may run at once on several threads.
    """
    for n in range(lo, hi):
        x.lift[r, n] = -1
        if x.drive_in[r, n]:
            w.mode[r, n] = Mode.DOCK
        elif x.centred[r, n]:
            w.mode[r, n] = Mode.CENTRE
            w.timer[r, n] = k.dock_ticks
        if w.mode[r, n] == Mode.CENTRE and w.timer[r, n] == 0:
            x.lift[r, n] = w.target[r, n]


@inlined
def dock_robots(r: int, lo: int, hi: int, w: World, x: Scratch) -> None:
    """Robots that drive in may overlap their carrier; centring ones stand on its centre."""
    for n in range(lo, hi):
        target = w.target[r, n]
        if x.drive_in[r, n]:
            w.ghost[r, n] = target
        if x.centred[r, n]:
            w.robot_pos[r, n, 0] = w.carrier_pos[r, target, 0]
            w.robot_pos[r, n, 1] = w.carrier_pos[r, target, 1]


@inlined
def answer_lifts(r: int, t: int, stamp: int, w: World, k: Constants, x: Scratch) -> bool:
    """The tags' answers to the lift writes (``world.answer_lifts``); whether any was accepted."""
    any_accepted = False
    # claims are judged on the state before any lift of this tick, smallest id first
    for n in range(k.robots):
        x.accepted[r, n] = False
        x.refused[r, n] = False
        c = x.lift[r, n]
        if c < 0:
            continue
        dx = w.robot_pos[r, n, 0] - w.carrier_pos[r, c, 0]
        dy = w.robot_pos[r, n, 1] - w.carrier_pos[r, c, 1]
        claim = (
            w.status[r, c] == TagStatus.AWAITING_PICKUP
            and w.carried_by[r, c] < 0
            and w.present[r, c]
            and w.ghost[r, n] == c
            and norm(dx, dy) <= k.arrival_tolerance
        )
        if claim and x.carrier_mark[r, c] != stamp:
            x.carrier_mark[r, c] = stamp
            x.accepted[r, n] = True
            any_accepted = True
        else:
            x.refused[r, n] = True
            emit(r, n, EventKind.LIFT_REFUSED, c, float(w.status[r, c]), x)
    for n in range(k.robots):
        if x.accepted[r, n]:
            c = x.lift[r, n]
            w.status[r, c] = TagStatus.PICKED_UP
            w.carried_by[r, c] = n
            w.pickup_time[r, c] = t
            emit(r, n, EventKind.LIFT, c, float(w.urgency[r, c]), x)
    return any_accepted


@inlined
def carry_robots(r: int, lo: int, hi: int, w: World, k: Constants, x: Scratch) -> None:
    """The ``carry`` step: lift, transport, release requests (``docking.carry``)."""
    for n in range(lo, hi):
        if x.refused[r, n]:
            to_walk(r, n, w)
        if x.accepted[r, n]:
            w.mode[r, n] = Mode.LIFT
            w.timer[r, n] = k.lift_ticks
        x.raised[r, n] = w.mode[r, n] == Mode.LIFT and w.timer[r, n] == 0
        if x.raised[r, n]:
            w.mode[r, n] = Mode.TRANSPORT
            w.stuck[r, n] = 0
            w.sidestep[r, n] = 0
            if not k.has_floor:
                high = k.arena - k.carrier_half
                y = minimum(maximum(w.robot_pos[r, n, 1], k.carrier_half), high)
                w.goal[r, n, 0] = k.transport_x
                w.goal[r, n, 1] = y
        if w.mode[r, n] == Mode.TRANSPORT and in_dropoff(r, n, w.target[r, n], w, k):
            w.mode[r, n] = Mode.RELEASE
            w.timer[r, n] = k.release_ticks
        x.lower[r, n] = -1
        if w.mode[r, n] == Mode.RELEASE and w.timer[r, n] == 0:
            x.lower[r, n] = w.target[r, n]
            to_walk(r, n, w)


@inlined
def _clear_of_obstacles(r: int, c: int, px: float, py: float, k: Constants, x: Scratch) -> bool:
    """Whether a robot at ``(px, py)`` overlaps no obstacle carrier other than ``c``."""
    count = x.obstacle_count[r]
    if k.obstacle_grid:
        reach = k.carrier_half + k.robot_radius
        count = near(
            r,
            px,
            py,
            reach,
            k.grid_cell,
            k.carrier_bits,
            x.obstacle_start,
            x.obstacle_items,
            x.near_blockers,
            False,
        )
    for j in range(count):
        i = x.near_blockers[r, j] if k.obstacle_grid else j
        if x.obstacles[r, i] == c:
            continue
        _, _, depth = contact(
            px - x.obstacle_x[r, i], py - x.obstacle_y[r, i], k.carrier_half, k.robot_radius, 1.0
        )
        if depth > 0:
            return False
    return True


@inlined
def free_faces_run(r: int, w: World, k: Constants, x: Scratch) -> None:
    """``predock.free_faces`` for every carrier of run ``r``: inside, clear of obstacles.

    Reads the run's obstacle index (``_index.index_obstacles``), which must be current.
    """
    low = k.robot_radius
    high = k.arena - k.robot_radius
    for c in range(k.carriers):
        cx = w.carrier_pos[r, c, 0]
        cy = w.carrier_pos[r, c, 1]
        for face in range(4):
            px = cx + FACE_X[face] * k.predock_offset
            py = cy + FACE_Y[face] * k.predock_offset
            if k.has_floor:
                free = clear_of_shelves(px, py, k.robot_radius, k)
            else:
                free = low <= px <= high and low <= py <= high
            w.free_face[r, c, face] = free and _clear_of_obstacles(r, c, px, py, k, x)


@inlined
def deliver_run(r: int, t: int, lifted: bool, w: World, k: Constants, x: Scratch) -> None:
    """Drive-offs, set-downs and IDLE writes (``world.deliver``); free faces after a lift."""
    for n in range(k.robots):
        if x.raised[r, n]:
            w.ghost[r, n] = -1
    for n in range(k.robots):
        c = x.lower[r, n]
        if c < 0:
            continue
        if w.status[r, c] != TagStatus.PICKED_UP:
            x.failure[r] = FAILURE_NOT_PICKED_UP
            continue
        if w.carried_by[r, c] != n or not in_dropoff(r, n, c, w, k):
            x.failure[r] = FAILURE_LOWERED
            continue
        w.status[r, c] = TagStatus.IDLE
        w.present[r, c] = False
        w.carried_by[r, c] = -1
        w.delivery_time[r, c] = t
        w.deliverer[r, c] = n
        w.delivery_urgency[r, c] = w.urgency[r, c]
        emit(r, n, EventKind.DELIVER, c, float(w.urgency[r, c]), x)
    if lifted:
        index_obstacles(r, w, k, x)  # one obstacle fewer
        free_faces_run(r, w, k, x)
