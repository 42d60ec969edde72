"""The built-in controller's ``decide`` step: pursuit checks, selection, walk directions.

In this order, for every robot at once (broken robots are the world's,
``swarmtag.sim.world.handling.break_down``):

1. a pursuing robot (PREDOCK, DOCK, CENTRE) abandons when the status it last
   heard from its target is not AWAITING_PICKUP, else times out when the
   pursuit has lasted ``timeout_ticks`` (that carrier is then barred to it
   for ``cooldown_ticks``); either way it returns to random walk;
2. with ``avoid_taken_faces``, a robot in PREDOCK whose predock point it
   sees taken by another robot (nearer to the point, within a robot
   diameter of it) moves on to the nearest free face not taken, if any;
3. a robot that was walking at the start of the tick selects, with the
   policy's ``select``, among its candidates: carriers whose position it
   knows from the camera, last heard as AWAITING_PICKUP, not cooling down
   for it and with a free predock face; it will dock at the free face whose
   predock point is nearest to it (with ``avoid_taken_faces``: the nearest
   not taken, if there is one). Each selection also records how many
   candidates there were (the ``candidates`` event). With BLE-led search
   (``radio_search``) every tag heard AWAITING_PICKUP (not cooling down,
   with a free face) is a candidate, its ``d`` the camera's distance where
   the position is known, else the robot's RSSI estimate; a chosen tag not
   seen is *sought*: the robot walks on (``seek``) and approaches the
   carrier once its camera sees it, the pursuit's checks and timeout
   applying from the choice on (a seeker chooses nothing else); with a
   look round (``look_ticks``) a walker that has a candidate first stands
   and turns for ``look_ticks`` ticks (``look``) and then chooses among
   what it saw meanwhile;
4. a walking robot that touched something last tick, or has just returned
   to walking, takes this tick's random direction, reversed if it points
   into what it touched (negative dot product with the contact push); so
   does a seeker that heard its tag more than ``seek_margin`` farther than
   the least on its current heading (run and tumble); with a turning walk,
   any other walking robot (not seeking) whose heading has been kept for
   ``walk_turn_ticks`` rotates it by this tick's turn; with a curved walk
   (``walk_curve``) a new heading comes with this tick's turn and every
   other walking robot (not seeking) rotates its heading by its leg's;
5. a loaded robot stuck for ``stuck_ticks`` starts a sidestep of
   ``sidestep_ticks`` along this tick's sidestep direction (reversed alike).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol

import numpy as np
from numpy.typing import NDArray

from swarmtag.policy import select
from swarmtag.sim.control.rules import away_from
from swarmtag.sim.model.events import EventKind, TickEvents
from swarmtag.sim.model.geometry import Float
from swarmtag.sim.model.indexing import PURSUIT_MODES, at_robots, grid, in_modes, own, to_walk
from swarmtag.sim.model.params import Params
from swarmtag.sim.model.randomness import TickInputs
from swarmtag.sim.model.state import Int, Mode, WorldState
from swarmtag.sim.world.predock import nearest_free_face, taken_faces
from swarmtag.sim.world.sensing import Senses
from swarmtag.sim.world.urgency import waited
from swarmtag.tag import TagStatus

__all__ = ["Chooser", "Selection", "decide"]

_AWAITING = int(TagStatus.AWAITING_PICKUP)


@dataclass(frozen=True, eq=False)
class Selection:
    """What a walking robot chooses from this tick, for an allocator (``Chooser``).

    ``available`` (R, N, C): each walker's candidates as the built-in rule
    has them (seen, last heard awaiting, not cooling down, a free face;
    after a look round); ``distance`` (R, N, C): the distances the rule
    scores (the camera's).
    """

    s: WorldState
    senses: Senses
    walkers: NDArray[np.bool_]
    available: NDArray[np.bool_]
    distance: Float
    inputs: TickInputs
    params: Params
    t: int


class Chooser(Protocol):
    """An allocator's choice step: which carrier each walker takes (-1 none)."""

    global_knowledge: bool
    """Pursuits are checked against the tags' true status (a central system), not what
    each robot heard."""

    def __call__(self, selection: Selection) -> tuple[Int, NDArray[np.float64]]:
        """Each robot's choice (R, N) and its candidate count for the ``candidates`` event."""
        ...


def _pursuit_checks(
    s: WorldState, params: Params, t: int, events: TickEvents, *, told: bool = False
) -> None:
    seeking = (s.mode == int(Mode.WALK)) & (s.seek >= 0)
    pursuing = in_modes(s.mode, PURSUIT_MODES) | seeking
    if not pursuing.any():
        return
    target = np.where(seeking, s.seek, s.target)
    heard = own(s.known_status, target) if not told else at_robots(s.status, target)
    abandon = pursuing & (heard != _AWAITING)
    timeout = pursuing & ~abandon & (t - s.pursuit_start >= params.timeout_ticks)
    events.add(EventKind.ABANDON, abandon, target, heard.astype(np.float64))
    events.add(EventKind.TIMEOUT, timeout, target, np.full(timeout.shape, np.nan))
    runs, robots = np.nonzero(timeout)
    s.blocked_until[runs, robots, target[runs, robots]] = t + params.cooldown_ticks
    to_walk(s, abandon | timeout)


def _taken(
    s: WorldState, centre: Float, params: Params, asking: NDArray[np.bool_]
) -> NDArray[np.bool_]:
    """(R, N, 4): the predock points of each robot's carrier it sees another robot stand on.

    Only for the robots ``asking`` (those whose answer is used); False for the others.
    """
    return taken_faces(
        s.robot_pos,
        centre,
        params.predock_offset,
        body=2 * params.robot_radius,
        sight=params.detection_radius,
        asking=asking,
    )


def _face(
    s: WorldState, carrier: Int, free: NDArray[np.bool_], params: Params, chosen: NDArray[np.bool_]
) -> Int:
    """The face each robot docks at on ``carrier`` (R, N): nearest free, avoiding taken ones.

    Only the faces of the robots in ``chosen`` (they chose a carrier) are meaningful.
    """
    centre = at_robots(s.carrier_pos, carrier)
    face = nearest_free_face(s.robot_pos, centre, free, params.predock_offset)
    if not params.avoid_taken_faces:
        return face
    taken = _taken(s, centre, params, chosen)
    open_face = nearest_free_face(s.robot_pos, centre, free & ~taken, params.predock_offset)
    return np.where(open_face >= 0, open_face, face)


def _switch_taken_faces(s: WorldState, params: Params) -> None:
    """Robots in PREDOCK whose point is taken move on to another free face not taken."""
    approaching = s.mode == int(Mode.PREDOCK)
    if not (params.avoid_taken_faces and approaching.any()):
        return
    centre = at_robots(s.carrier_pos, s.target)
    taken = _taken(s, centre, params, approaching)
    rows, robots = grid(*s.mode.shape)
    mine = taken[rows, robots, np.maximum(s.face, 0)]
    switch = approaching & mine
    if not switch.any():
        return
    free = at_robots(s.free_face, s.target) & ~taken
    other = nearest_free_face(s.robot_pos, centre, free, params.predock_offset)
    move = switch & (other >= 0)
    s.face[move] = other[move]


def _selection(
    s: WorldState,
    *,
    senses: Senses,
    walkers: NDArray[np.bool_],
    inputs: TickInputs,
    params: Params,
    t: int,
    events: TickEvents,
    chooser: Chooser | None,
) -> None:
    if not walkers.any():
        return
    open_tags = (
        (s.known_status == _AWAITING)
        & (s.blocked_until <= t)
        & np.any(s.free_face, axis=-1)[:, None, :]
    )
    distance = senses.distance
    if params.radio_search:
        walkers = walkers & ~_confirm(s, senses, walkers & (s.seek >= 0), open_tags, params)
        walkers &= s.seek < 0
        available = walkers[..., None] & open_tags  # every tag heard awaiting
        distance = np.where(senses.known, senses.distance, s.rssi)
    else:
        available = walkers[..., None] & senses.known & open_tags
        if params.look_ticks > 0:
            available = _look_round(s, walkers, available, t, params)
    if chooser is not None:
        selection = Selection(s, senses, walkers, available, distance, inputs, params, t)
        choice, candidates = chooser(selection)
    elif not available.any():
        return
    else:
        choice = select(
            params.policy,
            urgency=s.known_urgency,
            distance=distance,
            marker=params.markers,
            available=available,
            context=_context(s, params, t),
        ).astype(np.int64)
        candidates = available.sum(axis=-1).astype(np.float64)
    chosen = choice >= 0
    if not chosen.any():
        return
    rows, robots = grid(*choice.shape)
    heard = s.known_urgency[rows, robots, np.maximum(choice, 0)].astype(np.float64)
    events.add(EventKind.SELECT, chosen, choice, heard)
    events.add(EventKind.CANDIDATES, chosen, choice, candidates)
    s.pursuit_start[chosen] = t
    if params.radio_search:  # a tag not seen yet is sought by its signal
        seek = chosen & ~own(senses.known, choice)
        s.seek[seek] = choice[seek]
        s.seek_ref[seek] = own(s.rssi, choice)[seek]
        chosen &= ~seek
    _approach(s, choice, chosen, params)


def _context(s: WorldState, params: Params, t: int) -> dict[str, Float]:
    """What the policy asks for beside urgency, distance and marker (a rule of one's own)."""
    if "age" not in params.policy.context_names:
        return {}
    return {"age": waited(s.order_time, t, params.scenario.tick)[:, None, :]}


def _look_round(
    s: WorldState, walkers: NDArray[np.bool_], available: NDArray[np.bool_], t: int, params: Params
) -> NDArray[np.bool_]:
    """``available`` for the walkers whose look round ends now; the others look or walk on.

    A walker not looking that has a candidate begins to look (``look = t``:
    it stands and turns, ``motion.move``); one whose look has lasted
    ``look_ticks`` stops looking and chooses among what it saw meanwhile.
    """
    looking = walkers & (s.look >= 0)
    begin = walkers & ~looking & available.any(axis=-1)
    done = looking & (t - s.look >= params.look_ticks)
    s.look[begin] = t
    s.look[done] = -1
    chooses: NDArray[np.bool_] = available & done[..., None]
    return chooses


def _approach(s: WorldState, carrier: Int, chosen: NDArray[np.bool_], params: Params) -> None:
    """The robots ``chosen`` start the approach of their ``carrier`` (PREDOCK at a free face)."""
    face = _face(s, carrier, at_robots(s.free_face, carrier), params, chosen)
    s.mode[chosen] = Mode.PREDOCK
    s.target[chosen] = carrier[chosen]
    s.face[chosen] = face[chosen]


def _confirm(
    s: WorldState,
    senses: Senses,
    seekers: NDArray[np.bool_],
    open_tags: NDArray[np.bool_],
    params: Params,
) -> NDArray[np.bool_]:
    """Seekers whose camera now sees their tag's carrier approach it (BLE-led search).

    The pursuit started when the tag was chosen (its timeout counts from
    then). Returns the robots that did.
    """
    if not seekers.any():
        return seekers
    sought = np.maximum(s.seek, 0)
    confirmed: NDArray[np.bool_] = seekers & own(senses.known, sought) & own(open_tags, sought)
    _approach(s, sought, confirmed, params)
    s.seek[confirmed] = -1
    return confirmed


def _seek_tumbles(
    s: WorldState, walking: NDArray[np.bool_], fresh: NDArray[np.bool_], t: int, params: Params
) -> NDArray[np.bool_]:
    """``fresh`` plus the seekers that take a new heading as their tag's signal weakens.

    Run and tumble: a seeker keeps its heading while its estimate of the
    tag's distance stays within ``seek_margin`` of the least it heard on
    this leg (``seek_ref``) and takes a new random one when a hearing
    exceeds it; a new leg (any new heading) starts from the estimate then.
    """
    seeking = walking & (s.seek >= 0)
    sought = np.maximum(s.seek, 0)
    now = own(s.rssi, sought)
    heard = seeking & (own(s.heard_tick, sought) == t)
    tumble: NDArray[np.bool_] = fresh | (heard & (now > s.seek_ref * params.seek_margin))
    np.copyto(s.seek_ref, np.minimum(s.seek_ref, now), where=heard)
    np.copyto(s.seek_ref, now, where=seeking & tumble)
    return tumble


def _rotated(walk: Float, turn: Float, rotating: NDArray[np.bool_]) -> Float:
    """``walk`` rotated by ``turn`` ``(cos, sin)``, renormalised, where ``rotating``.

    The rotation is ``(x c - y s, x s + y c)``; elsewhere the values are not
    meant to be used (a robot not rotating may have no turn yet).
    """
    x, y = walk[..., 0], walk[..., 1]
    c, n = turn[..., 0], turn[..., 1]
    rx = x * c - y * n
    ry = x * n + y * c
    norm = np.where(rotating, np.sqrt(rx * rx + ry * ry), 1.0)
    rotated: Float = np.stack((rx / norm, ry / norm), axis=-1)
    return rotated


def _turn_walk(s: WorldState, walking: NDArray[np.bool_], turn: Float, every: int) -> None:
    """Rotate the walk direction of robots that kept it for ``every`` ticks by ``turn``."""
    s.walk_clock[walking] += 1
    due = walking & (s.walk_clock >= every)
    if not due.any():
        return
    np.copyto(s.walk, _rotated(s.walk, turn, due), where=due[..., None])
    s.walk_clock[due] = 0


def _curve_walk(
    s: WorldState, turning: NDArray[np.bool_], fresh: NDArray[np.bool_], turn: Float
) -> None:
    """A curved walk: each new leg takes this tick's turn, and every leg turns by its own.

    ``fresh`` robots (a new heading) and ``turning`` ones without a turn yet
    take ``turn``; the others that are ``turning`` rotate their walk by theirs.
    """
    unset = (s.curve[..., 0] == 0) & (s.curve[..., 1] == 0)
    np.copyto(s.curve, turn, where=(fresh | (turning & unset))[..., None])
    rotating = turning & ~fresh
    if not rotating.any():
        return
    np.copyto(s.walk, _rotated(s.walk, s.curve, rotating), where=rotating[..., None])


def decide(
    before: WorldState,
    s: WorldState,
    *,
    senses: Senses,
    inputs: TickInputs,
    params: Params,
    t: int,
    events: TickEvents,
    chooser: Chooser | None = None,
) -> None:
    """Apply the decisions of tick ``t`` to ``s`` in place (``before``: the state at tick start).

    ``chooser``: an allocator's choice step in place of the policy's ``select``
    (``swarmtag.sim.allocators``); everything else is the built-in controller's.
    """
    told = chooser is not None and chooser.global_knowledge
    _pursuit_checks(s, params, t, events, told=told)
    _switch_taken_faces(s, params)
    walkers = (before.mode == int(Mode.WALK)) & (s.mode == int(Mode.WALK))
    _selection(
        s, senses=senses, walkers=walkers, inputs=inputs, params=params, t=t, events=events,
        chooser=chooser,
    )  # fmt: skip

    bumped = (s.contact != 0).any(axis=-1)
    walking = s.mode == int(Mode.WALK)
    fresh = walking & (s.redirect | bumped)
    turning = walking
    if params.radio_search:
        fresh = _seek_tumbles(s, walking, fresh, t, params)
        turning = walking & (s.seek < 0)  # a seeker keeps its heading between hearings
    if fresh.any():
        np.copyto(s.walk, away_from(inputs.walk, s.contact), where=fresh[..., None])
        s.redirect[fresh] = False
    if params.walk_curve > 0 and inputs.turn is not None:
        _curve_walk(s, turning, fresh, inputs.turn)
    if params.walk_turn_ticks > 0 and inputs.turn is not None:
        _turn_walk(s, turning & ~fresh, inputs.turn, params.walk_turn_ticks)
        s.walk_clock[fresh] = 0

    unstick = (s.mode == int(Mode.TRANSPORT)) & (s.stuck >= params.stuck_ticks) & (s.sidestep == 0)
    if unstick.any():
        np.copyto(s.sidestep_dir, away_from(inputs.sidestep, s.contact), where=unstick[..., None])
        s.sidestep[unstick] = params.sidestep_ticks
        s.stuck[unstick] = 0
