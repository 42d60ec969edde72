"""Breakdowns and the built-in controller's ``decide`` step, compiled, robot by robot.

``break_down_robots`` is ``world.break_down``; ``decide_robots`` is
``sim/builtin/decide.py`` (pursuit checks, taken faces, selection with the policy's
``kernel_score``, walk and sidestep directions). A robot's decision reads the
other robots' positions but changes only its own fields, so any range of
robots can be decided independently.
"""

from __future__ import annotations

import math

import numpy as np

from swarmtag.policy._kernel import kernel_score
from swarmtag.sim.fast._events import emit
from swarmtag.sim.fast._geometry import FACE_X, FACE_Y, away_from, norm, unit_vector
from swarmtag.sim.fast._grid import near
from swarmtag.sim.fast._jit import inlined, jit
from swarmtag.sim.fast._layout import Constants, World
from swarmtag.sim.fast._scratch import Scratch
from swarmtag.sim.fast._tag_cache import block, known_blocked_until, known_status, known_urgency
from swarmtag.sim.model.events import EventKind
from swarmtag.sim.model.state import Mode
from swarmtag.tag import TagStatus

__all__ = ["break_down_robots", "decide_robots", "is_loaded", "to_walk"]


_score = jit(kernel_score)


@inlined
def is_loaded(mode: int, target: int) -> bool:
    """``_index.is_loaded`` for one robot."""
    return (Mode.LIFT <= mode <= Mode.RELEASE or mode == Mode.BROKEN) and target >= 0


@inlined
def to_walk(r: int, n: int, w: World) -> None:
    """``_index.to_walk`` for one robot."""
    w.mode[r, n] = Mode.WALK
    w.target[r, n] = -1
    w.face[r, n] = -1
    w.timer[r, n] = 0
    w.redirect[r, n] = True
    w.seek[r, n] = -1


@inlined
def break_down_robots(r: int, lo: int, hi: int, w: World, k: Constants, x: Scratch) -> None:
    """Robots whose breakdown number fired break down for good (``world.break_down``)."""
    if k.breakdown <= 0:
        return
    for n in range(lo, hi):
        mode = w.mode[r, n]
        if not (x.breakdown_draw[r, n] < k.breakdown) or mode == Mode.BROKEN:
            continue
        loaded = is_loaded(mode, w.target[r, n])
        emit(r, n, EventKind.BREAKDOWN, w.target[r, n] if loaded else -1, np.nan, x)
        if not loaded:
            w.target[r, n] = -1
        w.face[r, n] = -1
        w.mode[r, n] = Mode.BROKEN


@inlined
def _taken(
    r: int, n: int, cx: float, cy: float, face: int, w: World, k: Constants, x: Scratch
) -> bool:
    """``predock.taken_faces`` for one robot, carrier centre and face.

    With a grid, only the robots in cells within a body of the point are tried.
    """
    px = cx + FACE_X[face] * k.predock_offset
    py = cy + FACE_Y[face] * k.predock_offset
    rx = w.robot_pos[r, n, 0]
    ry = w.robot_pos[r, n, 1]
    mine = norm(rx - px, ry - py)
    body = 2 * k.robot_radius
    count = k.robots
    if k.robot_grid:
        count = near(
            r,
            px,
            py,
            body,
            k.grid_cell,
            k.robot_bits,
            x.robot_start,
            x.robot_items,
            x.near_robots,
            False,
        )
    for j in range(count):
        m = x.near_robots[r, j] if k.robot_grid else j
        if m == n:
            continue
        mx = w.robot_pos[r, m, 0]
        my = w.robot_pos[r, m, 1]
        gap = norm(mx - px, my - py)
        if gap < body and gap < mine and norm(rx - mx, ry - my) <= k.detection_radius:
            return True
    return False


@inlined
def _nearest_face(
    r: int, n: int, c: int, avoid_taken: bool, w: World, k: Constants, x: Scratch
) -> int:
    """``predock.nearest_free_face`` over the carrier's free faces (minus taken ones)."""
    cx = w.carrier_pos[r, c, 0]
    cy = w.carrier_pos[r, c, 1]
    rx = w.robot_pos[r, n, 0]
    ry = w.robot_pos[r, n, 1]
    best = -1
    best_distance = math.inf
    for face in range(4):
        if not w.free_face[r, c, face]:
            continue
        if avoid_taken and _taken(r, n, cx, cy, face, w, k, x):
            continue
        px = cx + FACE_X[face] * k.predock_offset
        py = cy + FACE_Y[face] * k.predock_offset
        distance = norm(px - rx, py - ry)
        if best < 0 or distance < best_distance:
            best = face
            best_distance = distance
    return best


@inlined
def _pursuit_check(r: int, n: int, t: int, w: World, k: Constants, x: Scratch) -> None:
    """Abandon unless AWAITING_PICKUP was heard, else time out (``decide._pursuit_checks``)."""
    mode = w.mode[r, n]
    seeking = mode == Mode.WALK and w.seek[r, n] >= 0
    if not (Mode.PREDOCK <= mode <= Mode.CENTRE or seeking):
        return
    target = w.seek[r, n] if seeking else w.target[r, n]
    heard = known_status(r, n, max(target, 0), w, k)
    if heard != TagStatus.AWAITING_PICKUP:
        emit(r, n, EventKind.ABANDON, target, float(heard), x)
        to_walk(r, n, w)
    elif t - w.pursuit_start[r, n] >= k.timeout_ticks:
        emit(r, n, EventKind.TIMEOUT, target, np.nan, x)
        block(r, n, target, t + k.cooldown_ticks, w, k)
        to_walk(r, n, w)


@inlined
def _switch_taken_face(r: int, n: int, w: World, k: Constants, x: Scratch) -> None:
    """A robot in PREDOCK whose point is taken moves on (``decide._switch_taken_faces``)."""
    if not k.avoid_taken_faces or w.mode[r, n] != Mode.PREDOCK:
        return
    target = w.target[r, n]
    cx = w.carrier_pos[r, target, 0]
    cy = w.carrier_pos[r, target, 1]
    if not _taken(r, n, cx, cy, max(w.face[r, n], 0), w, k, x):
        return
    other = _nearest_face(r, n, target, True, w, k, x)
    if other >= 0:
        w.face[r, n] = other


@inlined
def _open(r: int, n: int, c: int, t: int, w: World, k: Constants) -> bool:
    """Carrier ``c`` heard AWAITING_PICKUP, not cooling down for robot ``n``, with a free face."""
    return (
        known_status(r, n, c, w, k) == TagStatus.AWAITING_PICKUP
        and known_blocked_until(r, n, c, w, k) <= t
        and (
            w.free_face[r, c, 0]
            or w.free_face[r, c, 1]
            or w.free_face[r, c, 2]
            or w.free_face[r, c, 3]
        )
    )


@inlined
def _approach(r: int, n: int, c: int, w: World, k: Constants, x: Scratch) -> None:
    """Robot ``n`` starts the approach of carrier ``c`` at a free face (``decide._approach``)."""
    face = _nearest_face(r, n, c, False, w, k, x)
    if k.avoid_taken_faces:
        open_face = _nearest_face(r, n, c, True, w, k, x)
        if open_face >= 0:
            face = open_face
    w.mode[r, n] = Mode.PREDOCK
    w.target[r, n] = c
    w.face[r, n] = face


@inlined
def _seen_at(r: int, n: int, c: int, x: Scratch) -> int:
    """Where carrier ``c`` is in robot ``n``'s known carriers of this tick (-1: not known)."""
    for i in range(x.seen_count[r, n]):
        if x.seen_list[r, n, i] == c:
            return i
    return -1


@inlined
def _better(
    c: int, score: float, distance: float, best: int, best_score: float, best_distance: float
) -> bool:
    """The largest score, then the smaller distance, then the smaller marker (in any order)."""
    return (
        best < 0
        or score > best_score
        or (
            score == best_score
            and (distance < best_distance or (distance == best_distance and c < best))
        )
    )


@inlined
def _looked_round(r: int, n: int, t: int, w: World, k: Constants, x: Scratch) -> bool:
    """Whether robot ``n`` chooses now: its look round ends (``decide._look_round``).

    Not looking, it begins to look if it has a candidate (and chooses nothing).
    """
    look = w.look[r, n]
    if look < 0:
        for j in range(x.seen_count[r, n]):
            if _open(r, n, x.seen_list[r, n, j], t, w, k):
                w.look[r, n] = t
                break
        return False
    if t - look < k.look_ticks:
        return False
    w.look[r, n] = -1
    return True


@inlined
def _select(r: int, n: int, t: int, w: World, k: Constants, x: Scratch) -> None:
    """Choose among the candidates (``decide._selection`` with ``policy.select``'s tie rule).

    The candidates are the carriers the robot knows the position of this tick
    (``Scratch.seen_*``), heard AWAITING_PICKUP, not cooling down, with a free face.
    With BLE-led search, every such tag heard (``d``: the RSSI estimate where
    the camera does not know the carrier); a seeker only looks for its tag.
    """
    if k.radio_search and w.seek[r, n] >= 0:
        sought = w.seek[r, n]
        if _seen_at(r, n, sought, x) >= 0 and _open(r, n, sought, t, w, k):
            _approach(r, n, sought, w, k, x)
            w.seek[r, n] = -1
        return
    if k.look_ticks > 0 and not _looked_round(r, n, t, w, k, x):
        return
    best = -1
    best_score = 0.0
    best_distance = 0.0
    best_known = False
    count = 0
    # with search every carrier may be a candidate, else only those known from the camera
    total = k.carriers if k.radio_search else x.seen_count[r, n]
    for j in range(total):
        c = j if k.radio_search else x.seen_list[r, n, j]
        i = _seen_at(r, n, c, x) if k.radio_search else j
        if not _open(r, n, c, t, w, k):
            continue
        count += 1
        distance = x.seen_distance[r, n, i] if i >= 0 else w.rssi[r, n, c]
        urgency = float(known_urgency(r, n, c, w, k))
        score = _score(k.policy_kind, k.policy_parameter, urgency, distance)
        if _better(c, score, distance, best, best_score, best_distance):
            best = c
            best_score = score
            best_distance = distance
            best_known = i >= 0
    if best < 0:
        return
    emit(r, n, EventKind.SELECT, best, float(known_urgency(r, n, best, w, k)), x)
    emit(r, n, EventKind.CANDIDATES, best, float(count), x)
    w.pursuit_start[r, n] = t
    if best_known:
        _approach(r, n, best, w, k, x)
    else:  # a tag not seen yet is sought by its signal
        w.seek[r, n] = best
        w.seek_ref[r, n] = w.rssi[r, n, best]


@inlined
def _curve(
    r: int, n: int, fresh: bool, seeking: bool, outside: np.ndarray, row: int, w: World
) -> None:
    """A walking robot's curved walk (``decide._curve_walk``): a new leg's turn, or the leg's."""
    unset = w.curve[r, n, 0] == 0 and w.curve[r, n, 1] == 0
    if fresh or (unset and not seeking):
        w.curve[r, n, 0] = outside[r, row, n, 0]
        w.curve[r, n, 1] = outside[r, row, n, 1]
    if fresh or seeking:
        return
    _rotate_walk(r, n, w.curve[r, n, 0], w.curve[r, n, 1], w)


@inlined
def _rotate_walk(r: int, n: int, c: float, s: float, w: World) -> None:
    """Rotate robot ``n``'s walk direction by ``(c, s)``, renormalised (``decide._rotated``)."""
    hx = w.walk[r, n, 0]
    hy = w.walk[r, n, 1]
    rx = hx * c - hy * s
    ry = hx * s + hy * c
    length = math.sqrt(rx * rx + ry * ry)
    w.walk[r, n, 0] = rx / length
    w.walk[r, n, 1] = ry / length


@inlined
def _directions(
    r: int, n: int, t: int, outside: np.ndarray, row: int, w: World, k: Constants, x: Scratch
) -> None:
    """Fresh walk directions, the correlated walk's turn, sidesteps (end of ``decide``)."""
    push_x = w.contact[r, n, 0]
    push_y = w.contact[r, n, 1]
    walking = w.mode[r, n] == Mode.WALK
    fresh = walking and (w.redirect[r, n] or push_x != 0 or push_y != 0)
    seeking = k.radio_search and walking and w.seek[r, n] >= 0
    if seeking:  # run and tumble (``decide._seek_tumbles``)
        sought = w.seek[r, n]
        now = w.rssi[r, n, sought]
        if w.heard_tick[r, n, sought] == t:
            if now > w.seek_ref[r, n] * k.seek_margin:
                fresh = True
            w.seek_ref[r, n] = min(w.seek_ref[r, n], now)
        if fresh:
            w.seek_ref[r, n] = now
    if fresh:
        wx, wy = unit_vector(x.walk_gaussians[r, n, 0], x.walk_gaussians[r, n, 1])
        wx, wy = away_from(wx, wy, push_x, push_y)
        w.walk[r, n, 0] = wx
        w.walk[r, n, 1] = wy
        w.redirect[r, n] = False
    if k.walk_curve > 0 and walking:
        _curve(r, n, fresh, seeking, outside, row, w)
    if k.walk_turn_ticks > 0:
        if walking and not fresh and not seeking:
            w.walk_clock[r, n] += 1
            if w.walk_clock[r, n] >= k.walk_turn_ticks:
                _rotate_walk(r, n, outside[r, row, n, 0], outside[r, row, n, 1], w)
                w.walk_clock[r, n] = 0
        if fresh:
            w.walk_clock[r, n] = 0
    if w.mode[r, n] == Mode.TRANSPORT and w.stuck[r, n] >= k.stuck_ticks and w.sidestep[r, n] == 0:
        sx, sy = unit_vector(x.sidestep_gaussians[r, n, 0], x.sidestep_gaussians[r, n, 1])
        sx, sy = away_from(sx, sy, push_x, push_y)
        w.sidestep_dir[r, n, 0] = sx
        w.sidestep_dir[r, n, 1] = sy
        w.sidestep[r, n] = k.sidestep_ticks
        w.stuck[r, n] = 0


@inlined
def decide_robots(
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
    """The ``decide`` step of tick ``t`` for robots ``lo .. hi - 1`` of run ``r``.

    ``outside[r, row, n]`` holds robot ``n``'s walk turn ``(cos, sin)`` (``_tick.outside_row``).
    """
    for n in range(lo, hi):
        _pursuit_check(r, n, t, w, k, x)
        _switch_taken_face(r, n, w, k, x)
        if x.before_mode[r, n] == Mode.WALK and w.mode[r, n] == Mode.WALK:
            _select(r, n, t, w, k, x)
        _directions(r, n, t, outside, row, w, k, x)
