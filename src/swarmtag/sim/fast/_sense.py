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
    """Which tags of run ``r`` advertise during tick ``t`` (``sense.advertising``)."""
    after = (t - 1) * k.tick_us
    until = t * k.tick_us
    for c in range(k.carriers):
        phase = w.advert_phase[r, c]
        sent = (until - phase) // k.advert_us - (after - phase) // k.advert_us
        x.advertises[r, c] = sent > 0


@jit
def _line_of_sight(r: int, n: int, c: int, w: World, k: Constants) -> bool:
    """``sense.line_of_sight`` for one sighting: no other carrier (or robot) in the way."""
    sx = w.robot_pos[r, n, 0]
    sy = w.robot_pos[r, n, 1]
    ex = w.carrier_pos[r, c, 0]
    ey = w.carrier_pos[r, c, 1]
    for other in range(k.carriers):
        if other == c or not w.present[r, other] or w.carried_by[r, other] >= 0:
            continue
        if segment_crosses_box(
            sx, sy, ex, ey, w.carrier_pos[r, other, 0], w.carrier_pos[r, other, 1], k.carrier_half
        ):
            return False
    if k.occlusion >= 2:
        for m in range(k.robots):
            if m != n and segment_near_point(
                sx, sy, ex, ey, w.robot_pos[r, m, 0], w.robot_pos[r, m, 1], k.robot_radius
            ):
                return False
    return True


@jit
def sense_robots(r: int, t: int, lo: int, hi: int, w: World, k: Constants, x: Scratch) -> None:
    """Sense tick ``t`` for robots ``lo .. hi - 1`` of run ``r`` (``sense.sense``)."""
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
                visible = _line_of_sight(r, n, c, w, k)
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
