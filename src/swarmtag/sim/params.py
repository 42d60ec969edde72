"""Kernel parameters: the scenario and the policy in the kernel's units, frozen.

The kernel never sees seconds or degrees: durations are whole ticks, speeds
metres per tick, and the largest turn per tick is given as its cosine and
sine, computed here once (``math.cos``/``math.sin``, outside any kernel).
Other backends and the behaviour tree must take these numbers from
``Params`` rather than recompute them, so that they match bit for bit.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Final

import numpy as np
from numpy.typing import NDArray

from swarmtag.errors import ConfigError
from swarmtag.policy import Policy
from swarmtag.sim.floor_map import FloorMap
from swarmtag.sim.groups import seconds_to_ticks
from swarmtag.sim.scenario import Scenario
from swarmtag.sim.sensors import OCCLUSION_MODELS
from swarmtag.sim.warehouse import floor_of

__all__ = ["FIRST_CACHE_CAPACITY", "Params", "make_params", "sparse_tag_cache"]


@dataclass(frozen=True, eq=False)
class Params:
    """Everything the step kernel needs besides the state and the tick's random inputs.

    Lengths are metres, times ticks. The lab arena is ``[0, arena]^2``; the
    pick-up area is ``x <= pickup_right``, the drop-off area (destination 0)
    ``x >= dropoff_left``. A warehouse (``floor`` set) is
    ``[0, arena] x [0, arena_height]`` with its map's shelves and areas.
    """

    scenario: Scenario
    policy: Policy
    robots: int
    carriers: int
    arena: float
    pickup_right: float
    dropoff_left: float
    robot_radius: float
    carrier_half: float
    carrier_spacing: float
    step: float
    """Nominal distance a robot drives in one tick (speed times tick)."""
    turn_cos: float
    turn_sin: float
    """Cosine and sine of the largest turn in one tick."""
    detection_radius: float
    """Disc perception: the one detection radius. Split: the camera range (for pictures)."""
    split: bool
    """Split perception (radio and camera apart, SPEC §4.2a) rather than one detection disc."""
    radio_range: float
    camera_range: float
    occlusion: int
    """0: nothing blocks the camera; 1: other carriers do; 2: carriers and robots do."""
    memory_ticks: int
    """A sighting is remembered while ``t - seen <= memory_ticks`` (0: only this tick's)."""
    tick_us: int
    advert_us: int
    """Tick and advertising interval in whole microseconds: tags advertise on this grid."""
    walk_turn_ticks: int
    """A walking robot turns its heading every so many ticks (0: never, straight until contact)."""
    walk_turn_angle: float
    """Largest walk turn, radians (used only where the random step turns it into a unit vector)."""
    avoid_taken_faces: bool
    time_scale: float
    """Event-log time units per tick: 1 (logs in ticks) or ``tick`` (logs in seconds)."""
    predock_offset: float
    """Carrier centre to predock point: half the carrier side plus the predock distance."""
    arrival_tolerance: float
    """Metres within which a robot counts as standing on its predock point or carrier centre."""
    transport_x: float
    """x of a transport goal: the middle of the drop-off area."""
    dock_ticks: int
    lift_ticks: int
    release_ticks: int
    timeout_ticks: int
    cooldown_ticks: int
    stuck_ticks: int
    sidestep_ticks: int
    collision_iterations: int
    run_ticks: int
    growing: bool
    horizon: float
    """Growing model: T, the run length in ticks. Static model: the horizon in ticks."""
    advertisement_loss: float
    status_delay: int
    detection_noise: float
    speed_variation: float
    breakdown: float
    markers: NDArray[np.int64]
    """Marker id of each carrier (its index; in a warehouse, the order number)."""
    arena_height: float
    """The arena's extent in y (``arena`` in the lab; the map's height in a warehouse)."""
    floor: FloorMap | None
    """The warehouse floor (shelves, pick-up and drop-off cells); None in the lab arena."""
    sparse_tag_cache: bool
    """The compiled kernel keeps each robot's tag cache as a short list (``sparse_tag_cache``)."""

    @property
    def condition(self) -> str:
        """The policy's canonical condition name (SPEC §8.1)."""
        return self.policy.name


FIRST_CACHE_CAPACITY: Final = 64
"""Entries of each robot's sparse tag cache the compiled kernel tries first."""
SPARSE_FROM_PAIRS: Final = 65_536
"""Robot-carrier pairs of a run from which its tag caches are lists (below, the dense arrays
are small and their lookups faster: 20 robots and 40 carriers ran 25 % slower as lists,
the warehouse hall 30 %; docs/performance.md)."""


def sparse_tag_cache(scenario: Scenario) -> bool:
    """Whether the compiled kernel keeps ``scenario``'s robots' tag caches as short lists.

    Where the lists are exact (split perception with neither sighting memory
    nor the per-pair draws of advertisement loss and camera noise,
    ``sim/fast/_tag_cache.py``) and pay: from ``SPARSE_FROM_PAIRS``
    robot-carrier pairs a run (a warehouse's carriers are its orders, so its
    dense caches grow with the run). The compiled backend's states then
    carry no dense caches.
    """
    realism = scenario.realism
    exact = (
        scenario.perception == "split"
        and scenario.camera.memory == 0
        and realism.advertisement_loss == 0
        and realism.detection_noise == 0
    )
    return exact and scenario.robots * scenario.carriers >= SPARSE_FROM_PAIRS


def make_params(scenario: Scenario, policy: Policy) -> Params:
    """Kernel parameters for ``scenario`` under ``policy``.

    >>> from swarmtag.policy import Proximity
    >>> p = make_params(Scenario(), Proximity())
    >>> p.step, p.dock_ticks, p.timeout_ticks, round(p.turn_cos, 6)
    (0.05, 10, 300, 0.987688)
    """
    checked: object = policy
    if not isinstance(checked, Policy):
        msg = f"policy: {checked!r} is not a Policy; use swarmtag.policy.parse_policy(name)"
        raise ConfigError(msg)
    tick = scenario.tick
    arena, bodies, motion, timing = scenario.area, scenario.bodies, scenario.motion, scenario.timing
    turn = math.radians(min(motion.turn_rate * tick, 180.0))
    timeout = seconds_to_ticks(timing.pursuit_timeout, tick)
    if timeout < 1:
        msg = f"timing.pursuit_timeout: {timing.pursuit_timeout!r} s is shorter than one tick"
        raise ConfigError(msg)
    markers = np.arange(scenario.carriers, dtype=np.int64)
    markers.flags.writeable = False
    growing = scenario.urgency.model == "growing"
    horizon = float(scenario.ticks) if growing else scenario.urgency.static_horizon / tick
    floor, width, height = None, arena.size, arena.size
    if scenario.warehouse is not None:
        floor = floor_of(scenario.warehouse)
        width, height = floor.width, floor.height
        horizon = scenario.warehouse.urgency_window / tick
    return Params(
        scenario=scenario,
        policy=policy,
        robots=scenario.robots,
        carriers=scenario.carriers,
        arena=width,
        pickup_right=arena.pickup_width,
        dropoff_left=arena.size - arena.dropoff_width,
        robot_radius=bodies.robot_diameter / 2,
        carrier_half=bodies.carrier_size / 2,
        carrier_spacing=arena.carrier_spacing,
        step=motion.speed * tick,
        turn_cos=math.cos(turn),
        turn_sin=math.sin(turn),
        detection_radius=(
            scenario.camera.range if scenario.perception == "split" else scenario.detection_radius
        ),
        split=scenario.perception == "split",
        radio_range=scenario.radio.range,
        camera_range=scenario.camera.range,
        occlusion=OCCLUSION_MODELS.index(scenario.camera.occlusion),
        memory_ticks=seconds_to_ticks(scenario.camera.memory, tick),
        tick_us=max(1, round(tick * 1e6)),
        advert_us=max(1, round(scenario.radio.interval * 1e6)),
        walk_turn_ticks=(
            max(1, seconds_to_ticks(scenario.walk.turn_interval, tick))
            if scenario.walk.turn_interval > 0
            else 0
        ),
        walk_turn_angle=math.radians(scenario.walk.turn_angle),
        avoid_taken_faces=motion.avoid_taken_faces,
        time_scale=tick if scenario.time_unit == "s" else 1.0,
        predock_offset=bodies.carrier_size / 2 + motion.predock_distance,
        arrival_tolerance=motion.arrival_tolerance,
        transport_x=arena.size - arena.dropoff_width / 2,
        dock_ticks=seconds_to_ticks(timing.dock, tick),
        lift_ticks=seconds_to_ticks(timing.lift, tick),
        release_ticks=seconds_to_ticks(timing.release, tick),
        timeout_ticks=timeout,
        cooldown_ticks=seconds_to_ticks(timing.cooldown, tick),
        stuck_ticks=max(1, seconds_to_ticks(motion.stuck_time, tick)),
        sidestep_ticks=max(1, seconds_to_ticks(motion.sidestep_time, tick)),
        collision_iterations=motion.collision_iterations,
        run_ticks=scenario.run_ticks,
        growing=growing,
        horizon=horizon,
        advertisement_loss=scenario.realism.advertisement_loss,
        status_delay=scenario.realism.status_delay,
        detection_noise=scenario.realism.detection_noise,
        speed_variation=scenario.realism.speed_variation,
        breakdown=scenario.realism.breakdown,
        markers=markers,
        arena_height=height,
        floor=floor,
        sparse_tag_cache=sparse_tag_cache(scenario),
    )
