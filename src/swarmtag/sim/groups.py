"""The parts of a scenario, one frozen dataclass per concern (SPEC §4.1-§4.3).

Each part checks its own fields on construction and names them as a TOML
path (``arena.size``, ``timing.dock``); cross-part rules (bodies fit in the
zones, the predock stand-off clears the robot) live in ``Scenario``.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Final

from swarmtag._checks import (
    check_bool,
    check_choice,
    check_int,
    check_number,
    check_probability,
)
from swarmtag.errors import ConfigError

__all__ = [
    "LAB_CARRIERS",
    "MAX_DURATION",
    "MAX_LENGTH",
    "MAX_SPEED",
    "MAX_TICKS",
    "URGENCY_MODELS",
    "Arena",
    "Bodies",
    "Motion",
    "Realism",
    "Reprioritisation",
    "Timing",
    "UrgencyModel",
    "Walk",
    "seconds_to_ticks",
]

URGENCY_MODELS: Final = ("growing", "static")
LAB_CARRIERS: Final = 7
"""Carriers of the published lab set-up, whose arena is the reference for scaling."""
_LAB_SIDE: Final = 3.75
MAX_LENGTH: Final = 1e5
"""Largest length in metres (arena, ranges, bodies): 100 km, far beyond any warehouse."""
MAX_DURATION: Final = 1e7
"""Largest duration in seconds (timings, memory, horizons): about 116 days."""
MAX_SPEED: Final = 100.0
"""Largest speed in m/s and turn rate / 100 in degrees per second."""
MAX_TICKS: Final = 10**8
"""Most ticks of any run length or duration in ticks (with at least 100 us of work per tick,
a run of 10^8 ticks already takes hours)."""


def seconds_to_ticks(seconds: float, tick: float) -> int:
    """A duration in whole ticks, rounded to the nearest tick.

    >>> seconds_to_ticks(1.0, 0.1), seconds_to_ticks(0.3, 0.1), seconds_to_ticks(0.04, 0.1)
    (10, 3, 0)
    """
    return round(seconds / tick)


@dataclass(frozen=True, slots=True)
class Arena:
    """The square arena (metres): side, pick-up area at the left wall, drop-off at the right.

    ``carrier_spacing`` is the smallest gap between two carriers' edges; at
    least one robot diameter so that a robot fits between any two.
    """

    size: float = _LAB_SIDE
    pickup_width: float = 1.5
    dropoff_width: float = 0.75
    carrier_spacing: float = 0.25

    def __post_init__(self) -> None:
        for name in ("size", "pickup_width", "dropoff_width"):
            value = check_number(
                f"arena.{name}", getattr(self, name), low=0.0, low_open=True, high=MAX_LENGTH
            )
            object.__setattr__(self, name, value)
        spacing = check_number(
            "arena.carrier_spacing", self.carrier_spacing, low=0.0, high=MAX_LENGTH
        )
        object.__setattr__(self, "carrier_spacing", spacing)
        if self.pickup_width + self.dropoff_width > self.size:
            msg = (
                f"arena.pickup_width + arena.dropoff_width: {self.pickup_width!r} + "
                f"{self.dropoff_width!r} is more than arena.size {self.size!r}; "
                "the two areas must not overlap"
            )
            raise ConfigError(msg)

    @classmethod
    def scaled(cls, carriers: int, exponent: float = 0.5) -> Arena:
        """The lab arena scaled for ``carriers``: side and zones times (carriers / 7)^exponent.

        The default exponent 0.5 keeps the lab's carrier density (per square
        metre of arena and of pick-up area); fewer than 7 carriers keep the
        lab arena (the factor is at least 1).

        >>> Arena.scaled(7) == Arena() == Arena.scaled(2)
        True
        >>> round(Arena.scaled(28).size, 6), round(Arena.scaled(28, exponent=0.25).size, 6)
        (7.5, 5.303301)
        """
        factor = max(1.0, (carriers / LAB_CARRIERS) ** exponent)
        lab = cls()
        return cls(
            size=lab.size * factor,
            pickup_width=lab.pickup_width * factor,
            dropoff_width=lab.dropoff_width * factor,
            carrier_spacing=lab.carrier_spacing,
        )


@dataclass(frozen=True, slots=True)
class Bodies:
    """Robot disc diameter and carrier square side (metres), SPEC §4.1."""

    robot_diameter: float = 0.25
    carrier_size: float = 0.355

    def __post_init__(self) -> None:
        for name in ("robot_diameter", "carrier_size"):
            value = check_number(
                f"bodies.{name}", getattr(self, name), low=0.0, low_open=True, high=MAX_LENGTH
            )
            object.__setattr__(self, name, value)


@dataclass(frozen=True, slots=True)
class Motion:
    """Driving: top speed (m/s), turn rate (degrees/s), predock stand-off, unsticking.

    ``predock_distance`` is from the carrier face to the robot centre; a
    robot within ``arrival_tolerance`` of its predock point or of the
    carrier centre has arrived there.
    A loaded robot that has made less than a quarter of its step for
    ``stuck_time`` seconds sidesteps in a random direction for
    ``sidestep_time`` seconds. Collisions are resolved in
    ``collision_iterations`` Jacobi passes per tick. With
    ``avoid_taken_faces`` a robot heading for a predock point on which it
    sees another robot standing goes to another free face of its carrier
    (the remedy for herding robots locking each other out at one point).
    """

    speed: float = 0.5
    turn_rate: float = 90.0
    predock_distance: float = 0.175
    arrival_tolerance: float = 0.01
    stuck_time: float = 0.5
    sidestep_time: float = 0.5
    collision_iterations: int = 8
    avoid_taken_faces: bool = False

    def __post_init__(self) -> None:
        avoid = check_bool("motion.avoid_taken_faces", self.avoid_taken_faces)
        object.__setattr__(self, "avoid_taken_faces", avoid)
        highs = {
            "speed": MAX_SPEED,
            "turn_rate": MAX_SPEED * 100,
            "predock_distance": MAX_LENGTH,
            "arrival_tolerance": MAX_LENGTH,
            "stuck_time": MAX_DURATION,
            "sidestep_time": MAX_DURATION,
        }
        for name, high in highs.items():
            value = check_number(
                f"motion.{name}", getattr(self, name), low=0.0, low_open=True, high=high
            )
            object.__setattr__(self, name, value)
        iterations = check_int(
            "motion.collision_iterations", self.collision_iterations, low=1, high=1000
        )
        object.__setattr__(self, "collision_iterations", iterations)


@dataclass(frozen=True, slots=True)
class Walk:
    """How a searching robot wanders (SPEC §3.2 random walk).

    A walking robot always takes a new random heading when it touches a wall,
    a carrier or another robot. With ``turn_interval`` > 0 (seconds) it also
    turns its heading every ``turn_interval`` by an angle drawn uniformly
    from ``[-turn_angle, turn_angle]`` degrees (a correlated random walk; 180
    gives a fresh uniform heading); 0 keeps it straight until contact.
    """

    turn_interval: float = 0.0
    turn_angle: float = 180.0

    def __post_init__(self) -> None:
        interval = check_number(
            "walk.turn_interval", self.turn_interval, low=0.0, high=MAX_DURATION
        )
        object.__setattr__(self, "turn_interval", interval)
        angle = check_number("walk.turn_angle", self.turn_angle, low=0.0, high=180.0)
        object.__setattr__(self, "turn_angle", angle)


@dataclass(frozen=True, slots=True)
class Timing:
    """Behaviour durations in seconds (rounded to whole ticks).

    Dock = centring under the carrier, lift and release = the lifting
    mechanism; a pursuit longer than ``pursuit_timeout`` is given up and that
    robot may not re-select that carrier for ``cooldown``.
    """

    dock: float = 1.0
    lift: float = 1.0
    release: float = 1.0
    pursuit_timeout: float = 30.0
    cooldown: float = 30.0

    def __post_init__(self) -> None:
        for name in ("dock", "lift", "release", "cooldown"):
            value = check_number(f"timing.{name}", getattr(self, name), low=0.0, high=MAX_DURATION)
            object.__setattr__(self, name, value)
        timeout = check_number(
            "timing.pursuit_timeout",
            self.pursuit_timeout,
            low=0.0,
            low_open=True,
            high=MAX_DURATION,
        )
        object.__setattr__(self, "pursuit_timeout", timeout)


@dataclass(frozen=True, slots=True)
class UrgencyModel:
    """How urgencies arise (SPEC §4.3): ``growing`` or ``static``.

    ``static_time_limit`` (ticks) ends a static run that has not delivered
    everything; ``static_horizon`` (seconds, 240 in the SPEC) is the range
    of required delivery times.
    """

    model: str = "growing"
    static_time_limit: int = 6000
    static_horizon: float = 240.0

    def __post_init__(self) -> None:
        object.__setattr__(self, "model", check_choice("urgency.model", self.model, URGENCY_MODELS))
        limit = check_int(
            "urgency.static_time_limit", self.static_time_limit, low=1, high=MAX_TICKS
        )
        object.__setattr__(self, "static_time_limit", limit)
        horizon = check_number(
            "urgency.static_horizon", self.static_horizon, low=0.0, low_open=True, high=MAX_DURATION
        )
        object.__setattr__(self, "static_horizon", horizon)


@dataclass(frozen=True, slots=True)
class Realism:
    """Optional imperfections, all off by default (SPEC §4.2).

    ``advertisement_loss``: probability that a robot misses a tag's
    advertisement in a tick; ``status_delay``: ticks by which advertisements
    lag the tag's true state; ``detection_noise``: standard deviation (m) of
    the camera's carrier position per axis; ``speed_variation``: relative
    standard deviation of each robot's speed (factor clipped to 0.5-1.5);
    ``breakdown``: probability per robot per tick of breaking down for good.
    """

    advertisement_loss: float = 0.0
    status_delay: int = 0
    detection_noise: float = 0.0
    speed_variation: float = 0.0
    breakdown: float = 0.0

    def __post_init__(self) -> None:
        loss = check_number("realism.advertisement_loss", self.advertisement_loss, low=0.0, high=1)
        if loss == 1.0:
            msg = (
                "realism.advertisement_loss: 1.0 is not a number in [0, 1) (no tag would be heard)"
            )
            raise ConfigError(msg)
        object.__setattr__(self, "advertisement_loss", loss)
        object.__setattr__(
            self,
            "status_delay",
            check_int("realism.status_delay", self.status_delay, low=0, high=MAX_TICKS),
        )
        noise = check_number(
            "realism.detection_noise", self.detection_noise, low=0.0, high=MAX_LENGTH
        )
        object.__setattr__(self, "detection_noise", noise)
        variation = check_number("realism.speed_variation", self.speed_variation, low=0, high=1)
        object.__setattr__(self, "speed_variation", variation)
        object.__setattr__(
            self, "breakdown", check_probability("realism.breakdown", self.breakdown)
        )

    @property
    def enabled(self) -> bool:
        """True when any imperfection is switched on."""
        return any(
            (
                self.advertisement_loss,
                self.status_delay,
                self.detection_noise,
                self.speed_variation,
                self.breakdown,
            )
        )


@dataclass(frozen=True, slots=True)
class Reprioritisation:
    """An operator (WMS) write scheduled at ``tick``: set ``carrier``'s urgency to ``urgency``."""

    tick: int
    carrier: int
    urgency: int

    def __post_init__(self) -> None:
        tick = check_int("reprioritisations.tick", self.tick, low=1, high=MAX_TICKS)
        object.__setattr__(self, "tick", tick)
        carrier = check_int("reprioritisations.carrier", self.carrier, low=0, high=255)
        object.__setattr__(self, "carrier", carrier)
        urgency = check_int("reprioritisations.urgency", self.urgency, low=0, high=9)
        object.__setattr__(self, "urgency", urgency)
