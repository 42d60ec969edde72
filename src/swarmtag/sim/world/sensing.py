"""Phase 1 of a tick, sense: what each robot hears and sees (SPEC §4.2, §4.2a, §4.5).

Robots sense the world as it was at the end of the previous tick. Tags
advertise their state of ``status_delay`` ticks earlier; each robot keeps
the last status and urgency it heard per tag (its BLE cache). Two models:

- **split** (radio and camera apart, as on the robot). The radio hears tag
  c when c is in the arena, within ``radio.range``, advertised during this
  tick (once per advertising interval, at the tag's own phase, on a grid of
  whole microseconds) and the advertisement is not lost. The camera sees
  carrier c when it is in the arena and not carried, within
  ``camera.range`` (centre to centre; with a camera fade, within this
  tick's draw of the detection ramp; with a bearing profile, that reach
  times the profile's factor at the carrier's bearing from the robot's
  heading), and, with occlusion, the segment
  between the centres crosses no other such carrier's footprint (nor, with
  ``carriers+robots``, passes within a radius of another robot's centre).
  A sighting records the tick and the position seen (true position plus
  camera noise); the position is *known* while ``t - seen <= memory``.
  Without memory, only what a robot can act on is looked at: robots that
  were walking at the start of the tick, carriers they heard
  AWAITING_PICKUP (nothing else can become a candidate, so the outcome is
  the same and the costly line-of-sight tests are fewer).
- **disc** (the model before profiles). Carrier c within
  ``detection_radius`` is seen and heard (unless lost), every tick.

The distance used for selection is from the robot to the known position.
A robot looking round before it chooses (``camera.look_around``) knows
what it saw since its look began (``looked``).
With BLE-led search (``radio.search``) each heard advertisement also
updates the robot's running distance estimate of that tag from its RSSI
(``ranged``), which the controller uses for tags it has not seen.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Final

import numpy as np
from numpy.typing import NDArray

from swarmtag.sim.model.geometry import (
    Float,
    bearing_factor,
    length,
    length_xy,
    segment_crosses_box,
    segment_near_point,
)
from swarmtag.sim.model.params import Params
from swarmtag.sim.model.randomness import TickInputs
from swarmtag.sim.model.state import Int, Mode, WorldState
from swarmtag.sim.world.broad_phase import build_grid, grid_pays, near_segments
from swarmtag.sim.world.floor import hidden_by_shelves
from swarmtag.tag import TagStatus
from swarmtag.tag.advertising import adverts_sent

__all__ = [
    "Senses",
    "actionable",
    "advertised",
    "advertising",
    "drifted",
    "line_of_sight",
    "looked",
    "ranged",
    "sense",
    "sensed_state",
]

_SIGHT_CELL: Final = 0.75
"""Cell side (m) of the occluder grids: a line of sight spans a few such cells."""


@dataclass(frozen=True, eq=False)
class Senses:
    """What the robots perceive this tick, shapes (R, N, C) (positions (R, N, C, 2))."""

    known: NDArray[np.bool_]
    """Carrier position known from the camera: seen now or, with memory, recently."""
    distance: Float
    """Distance from the robot to the carrier's known position (camera noise included)."""
    known_status: NDArray[np.int8]
    """Each robot's cache of tag statuses after this tick's advertisements (-1 never heard)."""
    known_urgency: NDArray[np.int8]
    """Each robot's cache of tag urgencies after this tick's advertisements."""
    heard_tick: Int
    """Tick in which each robot last heard each tag, this tick's included (-1 never)."""
    seen_tick: Int
    """Tick of each robot's last sighting of each carrier, this tick's included (-1 never)."""
    seen_pos: Float
    """Where each robot last saw each carrier."""
    rssi: Float | None
    """Each robot's running RSSI distance estimate per tag after this tick (None: no search)."""
    odometry: Float | None = None
    """(R, N, 2) each robot's odometry error after this tick's growth (None: no drift)."""


def advertised(state: WorldState, params: Params) -> tuple[NDArray[np.int8], NDArray[np.int8]]:
    """Status and urgency the tags advertise during tick ``state.tick + 1``, shapes (R, C)."""
    slot = (state.tick - params.status_delay) % (params.status_delay + 1)
    return state.adv_status[:, slot], state.adv_urgency[:, slot]


def advertising(phase: Int, tick: int, params: Params) -> NDArray[np.bool_]:
    """Which tags send an advertisement during ``tick`` (1-based), shape of ``phase``.

    Tag c advertises at ``phase[c] + k * interval`` (microseconds); tick t
    covers ``((t - 1) * tick, t * tick]``. Integer arithmetic only.

    >>> from swarmtag.sim import Scenario, make_params
    >>> from swarmtag.policy import Proximity
    >>> p = make_params(Scenario(tick=0.1, perception="split"), Proximity())
    >>> [bool(advertising(np.array([0]), t, p)[0]) for t in range(1, 6)]
    [False, False, True, False, True]
    """
    sent: NDArray[np.bool_] = (
        adverts_sent(phase, params.advert_us, (tick - 1) * params.tick_us, tick * params.tick_us)
        > 0
    )
    return sent


def actionable(state: WorldState, known_status: NDArray[np.int8]) -> NDArray[np.bool_]:
    """(R, N, C): robots walking at the start of the tick and the carriers they heard awaiting.

    Only these sightings can make a candidate when there is no sighting memory.
    """
    walking = (state.mode == int(Mode.WALK))[..., None]
    awaiting: NDArray[np.bool_] = walking & (known_status == TagStatus.AWAITING_PICKUP)
    return awaiting


def line_of_sight(
    state: WorldState, visible: NDArray[np.bool_], params: Params
) -> NDArray[np.bool_]:
    """``visible`` (R, N, C) with the sightings whose line of sight is blocked removed.

    Occluders: other carriers in the arena and not carried (their squares),
    a warehouse's shelves, and with ``carriers+robots`` the other robots
    (their discs). Many
    occluders: only those near each line are tested
    (``swarmtag.sim.world.broad_phase``; the same result).
    """
    runs, robots, carriers = np.nonzero(visible)
    if runs.size == 0:
        return visible
    start = state.robot_pos[runs, robots]  # (K, 2)
    end = state.carrier_pos[runs, carriers]
    obstacle = state.present & (state.carried_by < 0)
    if not grid_pays("sight", runs.size, obstacle.shape[1]):
        others = state.carrier_pos[runs]  # (K, C, 2)
        blocking = obstacle[runs]
        blocking &= np.arange(state.carrier_pos.shape[1])[None, :] != carriers[:, None]
        half = params.carrier_half
        crosses = segment_crosses_box(start[:, None, :], end[:, None, :], others, half)
        blocked = (crosses & blocking).any(axis=1)
    else:
        blocked = _hidden_by_carriers(state, obstacle, (runs, carriers, start, end), params)
    if params.floor is not None:
        blocked |= hidden_by_shelves(start, end, params.floor)
    if params.occlusion >= 2:
        if not grid_pays("sight", runs.size, state.robot_pos.shape[1]):
            bodies = state.robot_pos[runs]  # (K, N, 2)
            radius = params.robot_radius
            near = segment_near_point(start[:, None, :], end[:, None, :], bodies, radius)
            near &= np.arange(state.robot_pos.shape[1])[None, :] != robots[:, None]
            blocked |= near.any(axis=1)
        else:
            blocked |= _hidden_by_robots(state, (runs, robots, start, end), params)
    result = visible.copy()
    result[runs[blocked], robots[blocked], carriers[blocked]] = False
    return result


_Lines = tuple[Int, Int, Float, Float]
"""Sightings: run, robot or carrier, start (K, 2), end (K, 2)."""


def _hidden_by_carriers(
    state: WorldState, obstacle: NDArray[np.bool_], lines: _Lines, params: Params
) -> NDArray[np.bool_]:
    """(K,): lines that cross another obstacle carrier's square (grid).

    A segment crosses the square only if the square's centre lies within
    ``carrier_half`` of the segment's bounding box.
    """
    runs, carriers, start, end = lines
    half = params.carrier_half
    pos = state.carrier_pos
    grid = build_grid(pos[..., 0], pos[..., 1], obstacle, _SIGHT_CELL)
    line, other = near_segments(grid, runs, start, end, half)
    crosses = segment_crosses_box(start[line], end[line], pos[runs[line], other], half)
    crosses &= other != carriers[line]
    blocked = np.zeros(runs.size, dtype=bool)
    blocked[line[crosses]] = True
    return blocked


def _hidden_by_robots(state: WorldState, lines: _Lines, params: Params) -> NDArray[np.bool_]:
    """(K,): lines that pass closer than a robot radius to another robot (grid)."""
    runs, robots, start, end = lines
    radius = params.robot_radius
    pos = state.robot_pos
    everyone = np.ones(pos.shape[:2], dtype=bool)
    grid = build_grid(pos[..., 0], pos[..., 1], everyone, _SIGHT_CELL)
    line, other = near_segments(grid, runs, start, end, radius)
    near = segment_near_point(start[line], end[line], pos[runs[line], other], radius)
    near &= other != robots[line]
    blocked = np.zeros(runs.size, dtype=bool)
    blocked[line[near]] = True
    return blocked


def sense(state: WorldState, inputs: TickInputs, params: Params) -> Senses:
    """Detections and the updated tag caches, from ``state`` (the end of the previous tick)."""
    t = state.tick + 1
    # (R, N, C) each robot's offset to each carrier, x and y apart (``length_xy``)
    dx = state.carrier_pos[:, None, :, 0] - state.robot_pos[:, :, None, 0]
    dy = state.carrier_pos[:, None, :, 1] - state.robot_pos[:, :, None, 1]
    distance = length_xy(dx, dy)
    present = state.present[:, None, :]
    if params.split:
        heard = present & (distance <= params.radio_range)
        heard &= advertising(state.advert_phase, t, params)[:, None, :]
        reach = params.camera_range if inputs.sight is None else inputs.sight
        if params.bearing_factor.size:
            heading = state.heading[:, :, None, :]
            factor = bearing_factor(
                dx, dy, distance, heading, cosines=params.bearing_cos, factors=params.bearing_factor
            )
            reach = reach * factor
        visible = present & (state.carried_by < 0)[:, None, :] & (distance <= reach)
    else:
        heard = visible = present & (distance <= params.detection_radius)
    if inputs.heard is not None:
        heard = heard & inputs.heard
    status, urgency = advertised(state, params)
    known_status = np.where(heard, status[:, None, :], state.known_status)
    known_urgency = np.where(heard, urgency[:, None, :], state.known_urgency)
    heard_tick = np.where(heard, t, state.heard_tick)
    rssi = ranged(state, heard, distance, inputs, params) if params.radio_search else None
    if params.split and params.memory_ticks == 0:
        visible = visible & actionable(state, known_status)
    if params.split and params.occlusion:
        visible = line_of_sight(state, visible, params)

    seen = state.carrier_pos[:, None, :, :]
    if inputs.noise is not None:
        seen = seen + inputs.noise
    odometry = drifted(state, inputs, params)
    believed = state.robot_pos  # where each robot believes it stands
    if odometry is not None:
        seen = seen + odometry[:, :, None, :]  # a sighting is kept in the robot's own frame
        believed = state.robot_pos + odometry
    seen_pos = state.seen_pos.copy()  # the new sightings written over the old (few a tick)
    seen_pos[visible] = np.broadcast_to(seen, seen_pos.shape)[visible]
    seen_tick = np.where(visible, t, state.seen_tick)
    if params.split and params.memory_ticks > 0:
        known = (seen_tick >= 0) & (t - seen_tick <= params.memory_ticks)
        known &= present
        measured = _distance_to_sightings(seen_pos, believed)
    else:
        known = visible
        measured = distance
        if inputs.noise is not None:
            measured = length_xy(dx + inputs.noise[..., 0], dy + inputs.noise[..., 1])
    if params.look_ticks > 0:
        known, measured = looked(
            state,
            seen_tick=seen_tick,
            seen=(seen_pos, believed),
            known=known,
            measured=measured,
            params=params,
        )
    return Senses(
        known=known,
        distance=measured,
        known_status=known_status,
        known_urgency=known_urgency,
        heard_tick=heard_tick,
        seen_tick=seen_tick,
        seen_pos=seen_pos,
        rssi=rssi,
        odometry=odometry,
    )


def _distance_to_sightings(seen_pos: Float, believed: Float) -> Float:
    """(R, N, C): from where each robot believes it stands to where it saw each carrier."""
    return length_xy(
        seen_pos[..., 0] - believed[:, :, None, 0], seen_pos[..., 1] - believed[:, :, None, 1]
    )


def drifted(state: WorldState, inputs: TickInputs, params: Params) -> Float | None:
    """(R, N, 2): the robots' odometry errors after the metres each drove since last tick.

    A random walk: each axis grows by ``g * drift * sqrt(moved)``, ``g``
    standard normal (the odometry stream), so its variance grows with the
    distance driven. None without drift.
    """
    if params.odometry_drift <= 0 or inputs.odometry is None:
        return None
    moved = length(state.robot_pos - state.odometry_at)
    step = params.odometry_drift * np.sqrt(moved)
    error: Float = state.odometry + inputs.odometry * step[..., None]
    return error


def looked(
    state: WorldState,
    *,
    seen_tick: Int,
    seen: tuple[Float, Float],
    known: NDArray[np.bool_],
    measured: Float,
    params: Params,
) -> tuple[NDArray[np.bool_], Float]:
    """``known`` and ``measured`` with what each robot looking round saw since it began.

    A walking robot with ``look >= 0`` knows every carrier in the arena its
    cameras saw since tick ``look`` (this tick's sightings included), at the
    distance from where it stands to where it saw each (as with memory;
    ``seen``: the sightings' positions and where the robots believe they stand).
    """
    seen_pos, believed = seen
    looking = ((state.look >= 0) & (state.mode == int(Mode.WALK)))[..., None]
    if not looking.any():
        return known, measured
    window = looking & (seen_tick >= state.look[..., None]) & state.present[:, None, :]
    if params.memory_ticks == 0:
        measured = np.where(looking, _distance_to_sightings(seen_pos, believed), measured)
    return known | window, measured


def ranged(
    state: WorldState, heard: NDArray[np.bool_], distance: Float, inputs: TickInputs, params: Params
) -> Float:
    """(R, N, C): the robots' RSSI distance estimates after this tick's advertisements.

    An advertisement heard gives the distance its RSSI implies (the true one
    times this tick's error factor); the estimate is that distance at a
    tag's first hearing, else moves ``rssi_smoothing`` of the way to it.
    """
    sample = distance if inputs.rssi is None else distance * inputs.rssi
    first = state.heard_tick < 0
    moved = state.rssi + params.rssi_smoothing * (sample - state.rssi)
    estimate: Float = np.where(heard, np.where(first, sample, moved), state.rssi)
    return estimate


def sensed_state(state: WorldState, senses: Senses) -> WorldState:
    """A copy of ``state`` as tick ``state.tick + 1`` begins, with the caches of ``senses``."""
    changes: dict[str, object] = {}
    if senses.rssi is not None:
        changes["rssi"] = senses.rssi
    if senses.odometry is not None:
        changes["odometry"] = senses.odometry
        changes["odometry_at"] = state.robot_pos.copy()
    return state.copy(
        tick=state.tick + 1,
        known_status=senses.known_status,
        known_urgency=senses.known_urgency,
        heard_tick=senses.heard_tick,
        seen_tick=senses.seen_tick,
        seen_pos=senses.seen_pos,
        **changes,
    )
