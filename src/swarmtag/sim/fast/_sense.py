"""Phase 1 of a compiled tick, sense: ``sim/world/sensing.py`` for one run, robot by robot.

Writes the robots' tag caches and sightings in place and leaves, per robot,
the carriers whose position it knows and the distance the policy uses to
each (``Scratch.seen_*``). Everything is read from the state at the end of
the previous tick, as in the reference. Where the run's index has grids
(``_index``), the camera and the lines of sight look only at the bodies
nearby; the tests they apply are the reference's.
"""

from __future__ import annotations

import math

import numpy as np

from swarmtag.sim.fast._floor import hidden_by_shelves
from swarmtag.sim.fast._geometry import bearing_factor, segment_crosses_box, segment_near_point
from swarmtag.sim.fast._grid import fill, near
from swarmtag.sim.fast._jit import inlined
from swarmtag.sim.fast._layout import Constants, World
from swarmtag.sim.fast._scratch import Scratch
from swarmtag.sim.fast._tag_cache import hear, known_status
from swarmtag.sim.model.state import Mode
from swarmtag.tag import TagStatus

__all__ = ["sense_robots", "tags_advertising"]


@inlined
def tags_advertising(r: int, t: int, w: World, k: Constants, x: Scratch) -> None:
    """Which tags of run ``r`` advertise during tick ``t`` (``sense.advertising``).

    Also lists those in the arena (``Scratch.advertising``). A tag sends in
    the tick's span ``(after, until]`` as often as a multiple of its interval
    past its phase lies in it: with ticks shorter than the interval, at most
    once, exactly when ``(until - phase) mod interval < tick``. That
    remainder is carried from tick to tick by an addition (two integer
    divisions a tag every tick were most of a small run's tick start).
    """
    after = (t - 1) * k.tick_us
    until = t * k.tick_us
    interval = k.advert_us
    carried = k.tick_us < interval and x.advert_tick[r] == t - 1
    x.advert_tick[r] = t
    count = 0
    for c in range(k.carriers):
        if carried:
            remainder = x.advert_remainder[r, c] + k.tick_us
            if remainder >= interval:
                remainder -= interval
            sent = 1 if remainder < k.tick_us else 0
        else:
            phase = w.advert_phase[r, c]
            remainder = (until - phase) % interval
            sent = (until - phase) // interval - (after - phase) // interval
        x.advert_remainder[r, c] = remainder
        x.advertises[r, c] = sent > 0
        if sent > 0 and w.present[r, c]:
            x.advertising[r, count] = c
            count += 1
    x.advertising_count[r] = count
    if k.radio_grid:
        for i in range(count):
            c = x.advertising[r, i]
            x.radio_x[r, i] = w.carrier_pos[r, c, 0]
            x.radio_y[r, i] = w.carrier_pos[r, c, 1]
        fill(
            r,
            x.radio_x,
            x.radio_y,
            count,
            k.radio_cell,
            k.carrier_bits,
            x.radio_start,
            x.radio_items,
            x.carrier_keys,
        )


@inlined
def _blocks(r: int, c: int, other: int, sx: float, sy: float, w: World, k: Constants) -> bool:
    """Whether carrier ``other`` (an obstacle) hides carrier ``c`` from the point ``(sx, sy)``."""
    if other == c or not w.present[r, other] or w.carried_by[r, other] >= 0:
        return False
    return segment_crosses_box(
        sx,
        sy,
        w.carrier_pos[r, c, 0],
        w.carrier_pos[r, c, 1],
        w.carrier_pos[r, other, 0],
        w.carrier_pos[r, other, 1],
        k.carrier_half,
    )


@inlined
def _hidden_by_carriers(r: int, n: int, c: int, w: World, k: Constants, x: Scratch) -> bool:
    """Whether another obstacle carrier crosses the line of sight from robot ``n`` to ``c``.

    The carrier that hid ``c`` from this robot last time is tried first (the
    answer does not depend on the order, and it usually still does); with a
    grid, only the obstacles in cells the segment's box (grown by a carrier's
    half side) touches are tried.
    """
    sx = w.robot_pos[r, n, 0]
    sy = w.robot_pos[r, n, 1]
    memo = not k.sparse_cache  # sparse caches keep no robot-carrier memo
    last = x.blocker[r, n, c] if memo else -1
    if last >= 0 and _blocks(r, c, last, sx, sy, w, k):
        return True
    if not k.obstacle_grid:
        for j in range(x.obstacle_count[r]):
            other = x.obstacles[r, j]
            if other != last and _blocks(r, c, other, sx, sy, w, k):
                if memo:
                    x.blocker[r, n, c] = other
                return True
        return False
    ex = w.carrier_pos[r, c, 0]
    ey = w.carrier_pos[r, c, 1]
    reach = max(abs(ex - sx), abs(ey - sy)) * 0.5 + k.carrier_half
    count = near(
        r,
        (sx + ex) * 0.5,
        (sy + ey) * 0.5,
        reach,
        k.sight_cell,
        k.carrier_bits,
        x.sight_start,
        x.sight_items,
        x.near_blockers,
        False,
    )
    for j in range(count):
        other = x.obstacles[r, x.near_blockers[r, j]]
        if other != last and _blocks(r, c, other, sx, sy, w, k):
            if memo:
                x.blocker[r, n, c] = other
            return True
    return False


@inlined
def _hidden_by_robots(r: int, n: int, c: int, w: World, k: Constants, x: Scratch) -> bool:
    """Whether the line of sight from robot ``n`` to carrier ``c`` passes near another robot."""
    sx = w.robot_pos[r, n, 0]
    sy = w.robot_pos[r, n, 1]
    ex = w.carrier_pos[r, c, 0]
    ey = w.carrier_pos[r, c, 1]
    count = k.robots
    if k.robot_grid:
        reach = max(abs(ex - sx), abs(ey - sy)) * 0.5 + k.robot_radius
        count = near(
            r,
            (sx + ex) * 0.5,
            (sy + ey) * 0.5,
            reach,
            k.sight_cell,
            k.robot_bits,
            x.crowd_start,
            x.crowd_items,
            x.near_robots,
            False,
        )
    for j in range(count):
        m = x.near_robots[r, j] if k.robot_grid else j
        if m != n and segment_near_point(
            sx, sy, ex, ey, w.robot_pos[r, m, 0], w.robot_pos[r, m, 1], k.robot_radius
        ):
            return True
    return False


@inlined
def _line_of_sight(r: int, n: int, c: int, w: World, k: Constants, x: Scratch) -> bool:
    """``sense.line_of_sight`` for one sighting: no other carrier (or robot) in the way."""
    if _hidden_by_carriers(r, n, c, w, k, x):
        return False
    sx = w.robot_pos[r, n, 0]
    sy = w.robot_pos[r, n, 1]
    if k.has_floor and hidden_by_shelves(sx, sy, w.carrier_pos[r, c, 0], w.carrier_pos[r, c, 1], k):
        return False
    return not (k.occlusion >= 2 and _hidden_by_robots(r, n, c, w, k, x))


@inlined
def _remember(r: int, n: int, c: int, distance: float, x: Scratch) -> None:
    """Add carrier ``c`` at ``distance`` to robot ``n``'s known carriers of this tick."""
    count = x.seen_count[r, n]
    x.seen_list[r, n, count] = c
    x.seen_distance[r, n, count] = distance
    x.seen_count[r, n] = count + 1


@inlined
def _camera(
    r: int, n: int, c: int, t: int, ox: float, oy: float, w: World, k: Constants, x: Scratch
) -> None:
    """Carrier ``c``, in range of robot ``n``'s camera (memory 0): a sighting if in view."""
    if k.occlusion > 0 and not _line_of_sight(r, n, c, w, k, x):
        return
    if k.sparse_cache:  # no sighting memory, no noise: only the distance is needed
        _remember(r, n, c, math.sqrt(ox * ox + oy * oy), x)
        return
    _sighting(r, n, c, t, w, k, x)
    if k.detection_noise > 0:
        dx = ox + x.noise[r, n, c, 0]
        dy = oy + x.noise[r, n, c, 1]
        _remember(r, n, c, math.sqrt(dx * dx + dy * dy), x)
    else:
        _remember(r, n, c, math.sqrt(ox * ox + oy * oy), x)


@inlined
def _sighting(r: int, n: int, c: int, t: int, w: World, k: Constants, x: Scratch) -> None:
    """Robot ``n`` sees carrier ``c`` now: the tick, and where (noise, in its own frame)."""
    sx = w.carrier_pos[r, c, 0]
    sy = w.carrier_pos[r, c, 1]
    if k.detection_noise > 0:
        sx = sx + x.noise[r, n, c, 0]
        sy = sy + x.noise[r, n, c, 1]
    if k.odometry_drift > 0:
        sx = sx + w.odometry[r, n, 0]
        sy = sy + w.odometry[r, n, 1]
    w.seen_pos[r, n, c, 0] = sx
    w.seen_pos[r, n, c, 1] = sy
    w.seen_tick[r, n, c] = t


@inlined
def _remembered(r: int, n: int, c: int, rx: float, ry: float, w: World, k: Constants) -> float:
    """Distance from where robot ``n`` believes it stands to where it saw carrier ``c``."""
    if k.odometry_drift > 0:
        rx = rx + w.odometry[r, n, 0]
        ry = ry + w.odometry[r, n, 1]
    dx = w.seen_pos[r, n, c, 0] - rx
    dy = w.seen_pos[r, n, c, 1] - ry
    return math.sqrt(dx * dx + dy * dy)


@inlined
def _drift(r: int, n: int, outside: np.ndarray, row: int, w: World, k: Constants) -> None:
    """Robot ``n``'s odometry error grows with the metres it drove (``sense.drifted``).

    Its Gaussian numbers are ``outside[r, row, n, 2:4]`` (the odometry stream).
    """
    px = w.robot_pos[r, n, 0]
    py = w.robot_pos[r, n, 1]
    mx = px - w.odometry_at[r, n, 0]
    my = py - w.odometry_at[r, n, 1]
    step = k.odometry_drift * math.sqrt(math.sqrt(mx * mx + my * my))  # drift * sqrt(metres)
    w.odometry[r, n, 0] = w.odometry[r, n, 0] + outside[r, row, n, 2] * step
    w.odometry[r, n, 1] = w.odometry[r, n, 1] + outside[r, row, n, 3] * step
    w.odometry_at[r, n, 0] = px
    w.odometry_at[r, n, 1] = py


@inlined
def _heard(
    r: int,
    n: int,
    c: int,
    t: int,
    slot: int,
    distance: float,
    outside: np.ndarray,
    row: int,
    w: World,
    k: Constants,
    x: Scratch,
) -> None:
    """Robot ``n`` hears tag ``c``: its cache and, with BLE-led search, its RSSI estimate.

    ``sense.ranged`` for one pair: the distance the RSSI implies (times this
    tick's error factor, ``outside[r, row, n, 4 + c]``) starts the estimate
    or moves it by ``rssi_smoothing``.
    """
    if k.radio_search:
        sample = distance
        if k.rssi_sigma > 0:
            sample = distance * outside[r, row, n, 4 + c]
        if w.heard_tick[r, n, c] < 0:
            w.rssi[r, n, c] = sample
        else:
            w.rssi[r, n, c] = w.rssi[r, n, c] + k.rssi_smoothing * (sample - w.rssi[r, n, c])
    hear(r, n, c, t, w.adv_status[r, slot, c], w.adv_urgency[r, slot, c], w, k, x)


@inlined
def _hear(
    r: int,
    n: int,
    t: int,
    slot: int,
    outside: np.ndarray,
    row: int,
    w: World,
    k: Constants,
    x: Scratch,
) -> None:
    """Robot ``n`` hears this tick's advertisements in range (split perception)."""
    rx = w.robot_pos[r, n, 0]
    ry = w.robot_pos[r, n, 1]
    count = x.advertising_count[r]
    if k.radio_grid:  # the tags in the cells around: the order of hearing changes nothing
        count = near(
            r,
            rx,
            ry,
            k.radio_cell,
            k.radio_cell,
            k.carrier_bits,
            x.radio_start,
            x.radio_items,
            x.near_carriers,
            False,
        )
    for i in range(count):
        c = x.advertising[r, x.near_carriers[r, i] if k.radio_grid else i]
        ox = w.carrier_pos[r, c, 0] - rx
        oy = w.carrier_pos[r, c, 1] - ry
        distance = math.sqrt(ox * ox + oy * oy)
        if not distance <= k.radio_range:
            continue
        if k.advertisement_loss > 0 and x.radio_draw[r, n, c] < k.advertisement_loss:
            continue
        _heard(r, n, c, t, slot, distance, outside, row, w, k, x)


@inlined
def _reach(
    r: int,
    n: int,
    c: int,
    ox: float,
    oy: float,
    distance: float,
    w: World,
    k: Constants,
    x: Scratch,
) -> float:
    """How far robot ``n`` sees carrier ``c`` (at offset ``ox, oy``) this tick.

    Its draw of the camera's ramp, or the range; with a bearing profile,
    times the factor at the carrier's bearing (``sense.sense``).
    """
    reach: float = k.camera_range
    if k.camera_fade > 0:
        reach = x.sight[r, n, c]
    if k.bearing:
        hx = w.heading[r, n, 0]
        hy = w.heading[r, n, 1]
        reach = reach * bearing_factor(
            ox, oy, distance, hx, hy, k.bearing_cosines, k.bearing_factors
        )
    return reach


@inlined
def _out_of_sight(r: int, rx: float, ry: float, k: Constants, x: Scratch) -> bool:
    """Whether every obstacle carrier is beyond the camera's range along x or y.

    The margin (a millionth of the range, many ulps) makes it safe against
    rounding: a carrier that far along one axis fails ``distance <= range``.
    """
    box = x.obstacle_box
    far = k.sight_reach * (1.0 + 1e-6) + 1e-9
    away: bool = (
        x.obstacle_count[r] == 0
        or rx - box[r, 1] > far
        or box[r, 0] - rx > far
        or ry - box[r, 3] > far
        or box[r, 2] - ry > far
    )
    return away


@inlined
def _sense_split_now(
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
    """Split perception without memory, doing only the work that can change something.

    The radio loop visits the tags that advertise this tick; the camera only
    matters for robots walking at the tick's start and the obstacle carriers
    they heard AWAITING_PICKUP (nothing else can be a candidate,
    ``sense.actionable``); the known carriers are only read for those robots.
    """
    slot = (t - 1 - k.status_delay) % (k.status_delay + 1)
    for n in range(lo, hi):
        _hear(r, n, t, slot, outside, row, w, k, x)
        x.seen_count[r, n] = 0
        if w.mode[r, n] != Mode.WALK:
            continue
        rx = w.robot_pos[r, n, 0]
        ry = w.robot_pos[r, n, 1]
        if not _out_of_sight(r, rx, ry, k, x):
            _camera_now(r, n, t, rx, ry, w, k, x)
        if k.look_ticks > 0 and w.look[r, n] >= 0:
            _looked(r, n, rx, ry, w, k, x)


@inlined
def _camera_now(
    r: int, n: int, t: int, rx: float, ry: float, w: World, k: Constants, x: Scratch
) -> None:
    """Walking robot ``n``'s sightings of the obstacle carriers it heard awaiting (memory 0)."""
    count = x.obstacle_count[r]
    if k.obstacle_grid:
        count = near(
            r,
            rx,
            ry,
            k.sight_reach,
            k.sight_cell,
            k.carrier_bits,
            x.sight_start,
            x.sight_items,
            x.near_carriers,
            False,
        )
    for j in range(count):
        c = x.obstacles[r, x.near_carriers[r, j] if k.obstacle_grid else j]
        if known_status(r, n, c, w, k) != TagStatus.AWAITING_PICKUP:
            continue
        ox = w.carrier_pos[r, c, 0] - rx
        oy = w.carrier_pos[r, c, 1] - ry
        distance = math.sqrt(ox * ox + oy * oy)
        if distance <= _reach(r, n, c, ox, oy, distance, w, k, x):
            _camera(r, n, c, t, ox, oy, w, k, x)


@inlined
def _looked(r: int, n: int, rx: float, ry: float, w: World, k: Constants, x: Scratch) -> None:
    """Robot ``n`` looking round knows what it saw since its look began (``sense.looked``).

    Its known carriers become every carrier in the arena seen since tick
    ``look``, at the distance from where it stands to where it saw each.
    """
    x.seen_count[r, n] = 0
    look = w.look[r, n]
    for c in range(k.carriers):
        if w.seen_tick[r, n, c] >= look and w.present[r, c]:
            _remember(r, n, c, _remembered(r, n, c, rx, ry, w, k), x)


@inlined
def sense_robots(
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
    """Sense tick ``t`` for robots ``lo .. hi - 1`` of run ``r`` (``sense.sense``).

    ``outside[r, row]``: the tick's numbers drawn outside the kernel (``_tick.outside_row``).
    """
    if k.odometry_drift > 0:
        for n in range(lo, hi):
            _drift(r, n, outside, row, w, k)
    if k.split and k.memory_ticks == 0:
        _sense_split_now(r, t, lo, hi, outside, row, w, k, x)
    else:
        _sense_every_pair(r, t, lo, hi, outside, row, w, k, x)


@inlined
def _sense_every_pair(
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
    """``sense.sense`` pair by pair: the disc model, and split perception with memory."""
    delay = k.status_delay
    slot = (t - 1 - delay) % (delay + 1)
    noisy = k.detection_noise > 0
    lossy = k.advertisement_loss > 0
    for n in range(lo, hi):
        rx = w.robot_pos[r, n, 0]
        ry = w.robot_pos[r, n, 1]
        x.seen_count[r, n] = 0
        looking = k.look_ticks > 0 and w.mode[r, n] == Mode.WALK and w.look[r, n] >= 0
        for c in range(k.carriers):
            ox = w.carrier_pos[r, c, 0] - rx
            oy = w.carrier_pos[r, c, 1] - ry
            distance = math.sqrt(ox * ox + oy * oy)
            present = w.present[r, c]
            if k.split:
                heard = present and distance <= k.radio_range and x.advertises[r, c]
                visible = (
                    present
                    and w.carried_by[r, c] < 0
                    and distance <= _reach(r, n, c, ox, oy, distance, w, k, x)
                )
            else:
                heard = present and distance <= k.detection_radius
                visible = heard
            if lossy and x.radio_draw[r, n, c] < k.advertisement_loss:
                heard = False
            if heard:
                _heard(r, n, c, t, slot, distance, outside, row, w, k, x)
            if k.split and k.occlusion > 0 and visible:
                visible = _line_of_sight(r, n, c, w, k, x)
            if visible:
                _sighting(r, n, c, t, w, k, x)
            if k.split:  # with memory (without, _sense_split_now senses)
                seen = w.seen_tick[r, n, c]
                recent = seen >= 0 and t - seen <= k.memory_ticks
                if looking and seen >= w.look[r, n]:
                    recent = True
                if recent and present:
                    _remember(r, n, c, _remembered(r, n, c, rx, ry, w, k), x)
            elif visible:
                if noisy:
                    dx = ox + x.noise[r, n, c, 0]
                    dy = oy + x.noise[r, n, c, 1]
                    _remember(r, n, c, math.sqrt(dx * dx + dy * dy), x)
                else:
                    _remember(r, n, c, distance, x)
