"""Phase 1 of a compiled tick, sense: ``sim/sense.py`` for one run, robot by robot.

Writes the robots' tag caches and sightings in place and leaves, per robot
and carrier, whether its position is known and the distance the policy uses
(``Scratch.known``, ``Scratch.measured``). Everything is read from the state
at the end of the previous tick, as in the reference.
"""

from __future__ import annotations

import math

from swarmtag.sim.fast._geometry import segment_crosses_box, segment_near_point
from swarmtag.sim.fast._jit import jit
from swarmtag.sim.fast._layout import Constants, Scratch, World

__all__ = ["sense_robots", "tags_advertising"]

_WALK = 0
_AWAITING = 1


@jit
def tags_advertising(r: int, t: int, w: World, k: Constants, x: Scratch) -> None:
    """Which tags of run ``r`` advertise during tick ``t`` (``sense.advertising``).

    Also lists those in the arena (``Scratch.advertising``).
    """
    after = (t - 1) * k.tick_us
    until = t * k.tick_us
    count = 0
    for c in range(k.carriers):
        phase = w.advert_phase[r, c]
        sent = (until - phase) // k.advert_us - (after - phase) // k.advert_us
        x.advertises[r, c] = sent > 0
        if sent > 0 and w.present[r, c]:
            x.advertising[r, count] = c
            count += 1
    x.advertising_count[r] = count


@jit
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


@jit
def _line_of_sight(r: int, n: int, c: int, w: World, k: Constants, x: Scratch) -> bool:
    """``sense.line_of_sight`` for one sighting: no other carrier (or robot) in the way.

    The carrier that hid ``c`` from this robot last time is tried first (the
    answer does not depend on the order, and it usually still does).
    """
    sx = w.robot_pos[r, n, 0]
    sy = w.robot_pos[r, n, 1]
    last = x.blocker[r, n, c]
    if last >= 0 and _blocks(r, c, last, sx, sy, w, k):
        return False
    for other in range(k.carriers):
        if other != last and _blocks(r, c, other, sx, sy, w, k):
            x.blocker[r, n, c] = other
            return False
    if k.occlusion >= 2:
        ex = w.carrier_pos[r, c, 0]
        ey = w.carrier_pos[r, c, 1]
        for m in range(k.robots):
            if m != n and segment_near_point(
                sx, sy, ex, ey, w.robot_pos[r, m, 0], w.robot_pos[r, m, 1], k.robot_radius
            ):
                return False
    return True


@jit
def _camera(
    r: int, n: int, c: int, t: int, ox: float, oy: float, w: World, k: Constants, x: Scratch
) -> None:
    """Carrier ``c`` seen now by robot ``n`` (memory 0): its sighting, known, measured distance."""
    if k.occlusion > 0 and not _line_of_sight(r, n, c, w, k, x):
        x.known[r, n, c] = False
        return
    if k.detection_noise > 0:
        w.seen_pos[r, n, c, 0] = w.carrier_pos[r, c, 0] + x.noise[r, n, c, 0]
        w.seen_pos[r, n, c, 1] = w.carrier_pos[r, c, 1] + x.noise[r, n, c, 1]
        dx = ox + x.noise[r, n, c, 0]
        dy = oy + x.noise[r, n, c, 1]
        x.measured[r, n, c] = math.sqrt(dx * dx + dy * dy)
    else:
        w.seen_pos[r, n, c, 0] = w.carrier_pos[r, c, 0]
        w.seen_pos[r, n, c, 1] = w.carrier_pos[r, c, 1]
        x.measured[r, n, c] = math.sqrt(ox * ox + oy * oy)
    w.seen_tick[r, n, c] = t
    x.known[r, n, c] = True


@jit
def _sense_split_now(r: int, t: int, lo: int, hi: int, w: World, k: Constants, x: Scratch) -> None:
    """Split perception without memory, doing only the work that can change something.

    The radio loop visits the tags that advertise this tick; the camera only
    matters for robots walking at the tick's start and carriers they heard
    AWAITING_PICKUP (nothing else can be a candidate, ``sense.actionable``),
    and ``known``/``measured`` are only read for those robots.
    """
    slot = (t - 1 - k.status_delay) % (k.status_delay + 1)
    lossy = k.advertisement_loss > 0
    for n in range(lo, hi):
        rx = w.robot_pos[r, n, 0]
        ry = w.robot_pos[r, n, 1]
        for i in range(x.advertising_count[r]):
            c = x.advertising[r, i]
            ox = w.carrier_pos[r, c, 0] - rx
            oy = w.carrier_pos[r, c, 1] - ry
            if not math.sqrt(ox * ox + oy * oy) <= k.radio_range:
                continue
            if lossy and x.radio_draw[r, n, c] < k.advertisement_loss:
                continue
            w.known_status[r, n, c] = w.adv_status[r, slot, c]
            w.known_urgency[r, n, c] = w.adv_urgency[r, slot, c]
            w.heard_tick[r, n, c] = t
        if w.mode[r, n] != _WALK:
            continue
        for c in range(k.carriers):
            x.known[r, n, c] = False
            if (
                w.known_status[r, n, c] != _AWAITING
                or not w.present[r, c]
                or w.carried_by[r, c] >= 0
            ):
                continue
            ox = w.carrier_pos[r, c, 0] - rx
            oy = w.carrier_pos[r, c, 1] - ry
            if math.sqrt(ox * ox + oy * oy) <= k.camera_range:
                _camera(r, n, c, t, ox, oy, w, k, x)


@jit
def sense_robots(r: int, t: int, lo: int, hi: int, w: World, k: Constants, x: Scratch) -> None:
    """Sense tick ``t`` for robots ``lo .. hi - 1`` of run ``r`` (``sense.sense``)."""
    if k.split and k.memory_ticks == 0:
        _sense_split_now(r, t, lo, hi, w, k, x)
    else:
        _sense_every_pair(r, t, lo, hi, w, k, x)


@jit
def _sense_every_pair(r: int, t: int, lo: int, hi: int, w: World, k: Constants, x: Scratch) -> None:
    """``sense.sense`` pair by pair: the disc model, and split perception with memory."""
    delay = k.status_delay
    slot = (t - 1 - delay) % (delay + 1)
    noisy = k.detection_noise > 0
    lossy = k.advertisement_loss > 0
    for n in range(lo, hi):
        rx = w.robot_pos[r, n, 0]
        ry = w.robot_pos[r, n, 1]
        walking = w.mode[r, n] == _WALK
        for c in range(k.carriers):
            ox = w.carrier_pos[r, c, 0] - rx
            oy = w.carrier_pos[r, c, 1] - ry
            distance = math.sqrt(ox * ox + oy * oy)
            present = w.present[r, c]
            if k.split:
                heard = present and distance <= k.radio_range and x.advertises[r, c]
                visible = present and w.carried_by[r, c] < 0 and distance <= k.camera_range
            else:
                heard = present and distance <= k.detection_radius
                visible = heard
            if lossy and x.radio_draw[r, n, c] < k.advertisement_loss:
                heard = False
            if heard:
                w.known_status[r, n, c] = w.adv_status[r, slot, c]
                w.known_urgency[r, n, c] = w.adv_urgency[r, slot, c]
                w.heard_tick[r, n, c] = t
            if k.split and k.memory_ticks == 0:
                visible = visible and walking and w.known_status[r, n, c] == _AWAITING
            if k.split and k.occlusion > 0 and visible:
                visible = _line_of_sight(r, n, c, w, k, x)
            if visible:
                if noisy:
                    w.seen_pos[r, n, c, 0] = w.carrier_pos[r, c, 0] + x.noise[r, n, c, 0]
                    w.seen_pos[r, n, c, 1] = w.carrier_pos[r, c, 1] + x.noise[r, n, c, 1]
                else:
                    w.seen_pos[r, n, c, 0] = w.carrier_pos[r, c, 0]
                    w.seen_pos[r, n, c, 1] = w.carrier_pos[r, c, 1]
                w.seen_tick[r, n, c] = t
            if k.split and k.memory_ticks > 0:
                seen = w.seen_tick[r, n, c]
                x.known[r, n, c] = seen >= 0 and t - seen <= k.memory_ticks and present
                dx = w.seen_pos[r, n, c, 0] - rx
                dy = w.seen_pos[r, n, c, 1] - ry
                x.measured[r, n, c] = math.sqrt(dx * dx + dy * dy)
            else:
                x.known[r, n, c] = visible
                if noisy:
                    dx = ox + x.noise[r, n, c, 0]
                    dy = oy + x.noise[r, n, c, 1]
                    x.measured[r, n, c] = math.sqrt(dx * dx + dy * dy)
                else:
                    x.measured[r, n, c] = distance
