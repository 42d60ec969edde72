"""The parts of a scenario, one frozen dataclass per concern (SPEC §4.1-§4.3).

Each part checks its own fields on construction and names them as a TOML
path (``arena.size``, ``timing.dock``); cross-part rules (bodies fit in the
zones, the predock stand-off clears the robot) live in ``Scenario``.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Final

from swarmtag._checks import check_int
from swarmtag.errors import ConfigError
from swarmtag.sim.config.schema import (
    PER_TICK,
    RADIANS,
    TICKS,
    TICKS_AT_LEAST_ONE,
    Kernel,
    check_part,
    param,
    seconds_to_ticks,
)

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


@dataclass(frozen=True, slots=True)
class Arena:
    """The square arena (metres): side, pick-up area at the left wall, drop-off at the right.

    ``carrier_spacing`` is the smallest gap between two carriers' edges; at
    least one robot diameter so that a robot fits between any two.
    """

    size: float = param(
        _LAB_SIDE,
        unit="m",
        doc="Side of the square arena.",
        low=0.0,
        low_open=True,
        high=MAX_LENGTH,
    )
    pickup_width: float = param(
        1.5,
        unit="m",
        doc="Width of the pick-up area along the left wall.",
        low=0.0,
        low_open=True,
        high=MAX_LENGTH,
        kernel=Kernel("pickup_right"),
    )
    dropoff_width: float = param(
        0.75,
        unit="m",
        doc="Width of the drop-off area along the right wall.",
        low=0.0,
        low_open=True,
        high=MAX_LENGTH,
    )
    carrier_spacing: float = param(
        0.25,
        unit="m",
        doc="Smallest gap between two carriers' edges.",
        low=0.0,
        high=MAX_LENGTH,
        kernel=Kernel("carrier_spacing"),
    )

    def __post_init__(self) -> None:
        check_part(self, "arena")
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

    robot_diameter: float = param(
        0.25,
        unit="m",
        doc="Diameter of a robot's disc.",
        low=0.0,
        low_open=True,
        high=MAX_LENGTH,
    )
    carrier_size: float = param(
        0.355,
        unit="m",
        doc="Side of a carrier's square.",
        low=0.0,
        low_open=True,
        high=MAX_LENGTH,
    )

    def __post_init__(self) -> None:
        check_part(self, "bodies")


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

    speed: float = param(
        0.5,
        unit="m/s",
        doc="Top speed.",
        low=0.0,
        low_open=True,
        high=MAX_SPEED,
        kernel=Kernel("step", PER_TICK),
    )
    turn_rate: float = param(
        90.0,
        unit="deg/s",
        doc="Largest turn rate (predock).",
        low=0.0,
        low_open=True,
        high=MAX_SPEED * 100,
    )
    predock_distance: float = param(
        0.175,
        unit="m",
        doc="From the carrier's face to the robot's centre at the predock point.",
        low=0.0,
        low_open=True,
        high=MAX_LENGTH,
    )
    arrival_tolerance: float = param(
        0.01,
        unit="m",
        doc="Within this of its predock point or carrier centre, a robot is there.",
        low=0.0,
        low_open=True,
        high=MAX_LENGTH,
        kernel=Kernel("arrival_tolerance", controller=True),
    )
    stuck_time: float = param(
        0.5,
        unit="s",
        doc="A loaded robot this long stuck starts a sidestep.",
        low=0.0,
        low_open=True,
        high=MAX_DURATION,
        kernel=Kernel("stuck_ticks", TICKS_AT_LEAST_ONE, controller=True),
    )
    sidestep_time: float = param(
        0.5,
        unit="s",
        doc="How long a sidestep lasts.",
        low=0.0,
        low_open=True,
        high=MAX_DURATION,
        kernel=Kernel("sidestep_ticks", TICKS_AT_LEAST_ONE, controller=True),
    )
    collision_iterations: int = param(
        8,
        unit="",
        doc="Jacobi passes resolving collisions each tick.",
        low=1,
        high=1000,
        kernel=Kernel("collision_iterations"),
    )
    avoid_taken_faces: bool = param(
        False,
        unit="",
        doc="Switch from a predock point another robot stands on.",
        kernel=Kernel("avoid_taken_faces", controller=True),
    )

    def __post_init__(self) -> None:
        check_part(self, "motion")


@dataclass(frozen=True, slots=True)
class Walk:
    """How a searching robot wanders (SPEC §3.2 random walk).

    A walking robot always takes a new random heading when it touches a wall,
    a carrier or another robot. With ``turn_interval`` > 0 (seconds) it also
    turns its heading every ``turn_interval`` by an angle drawn uniformly
    from ``[-turn_angle, turn_angle]`` degrees (a correlated random walk; 180
    gives a fresh uniform heading); 0 keeps it straight until contact. With
    ``curve`` > 0 (degrees per second) the walk is curved instead, as the
    lab's example controllers drive: each new heading comes with an angular
    velocity drawn uniformly from ``[-curve, curve]`` that turns the heading
    every tick until the next one (the controllers draw from ±90°/s).
    """

    turn_interval: float = param(
        0.0,
        unit="s",
        doc="A walking robot turns this often (0: straight until contact).",
        low=0.0,
        high=MAX_DURATION,
    )
    turn_angle: float = param(
        180.0,
        unit="deg",
        doc="Largest walk turn (uniform in [-angle, angle]).",
        low=0.0,
        high=180.0,
        kernel=Kernel("walk_turn_angle", RADIANS),
    )
    curve: float = param(
        0.0,
        unit="deg/s",
        doc="Largest angular velocity of a curved walk's leg (0: straight legs).",
        low=0.0,
        high=3600.0,
    )

    def __post_init__(self) -> None:
        check_part(self, "walk")
        if self.curve > 0 and self.turn_interval > 0:
            msg = (
                f"walk.curve: {self.curve!r} deg/s with walk.turn_interval "
                f"{self.turn_interval!r} s (a walk either turns now and then or curves; "
                "set one of them to 0)"
            )
            raise ConfigError(msg)


@dataclass(frozen=True, slots=True)
class Timing:
    """Behaviour durations in seconds (rounded to whole ticks).

    Dock = centring under the carrier, lift and release = the lifting
    mechanism; a pursuit longer than ``pursuit_timeout`` is given up and that
    robot may not re-select that carrier for ``cooldown``.
    """

    dock: float = param(
        1.0,
        unit="s",
        doc="Centring under the carrier.",
        low=0.0,
        high=MAX_DURATION,
        kernel=Kernel("dock_ticks", TICKS, controller=True),
    )
    lift: float = param(
        1.0,
        unit="s",
        doc="Raising the lifting mechanism.",
        low=0.0,
        high=MAX_DURATION,
        kernel=Kernel("lift_ticks", TICKS, controller=True),
    )
    release: float = param(
        1.0,
        unit="s",
        doc="Lowering the lifting mechanism.",
        low=0.0,
        high=MAX_DURATION,
        kernel=Kernel("release_ticks", TICKS, controller=True),
    )
    pursuit_timeout: float = param(
        30.0,
        unit="s",
        doc="A pursuit longer than this is given up.",
        low=0.0,
        low_open=True,
        high=MAX_DURATION,
    )
    cooldown: float = param(
        30.0,
        unit="s",
        doc="A carrier given up on by timeout is not chosen again for this long.",
        low=0.0,
        high=MAX_DURATION,
        kernel=Kernel("cooldown_ticks", TICKS, controller=True),
    )

    def __post_init__(self) -> None:
        check_part(self, "timing")


@dataclass(frozen=True, slots=True)
class UrgencyModel:
    """How urgencies arise (SPEC §4.3): ``growing`` or ``static``.

    ``static_time_limit`` (ticks) ends a static run that has not delivered
    everything; ``static_horizon`` (seconds, 240 in the SPEC) is the range
    of required delivery times.
    """

    model: str = param("growing", unit="", doc="How urgencies arise.", choices=URGENCY_MODELS)
    static_time_limit: int = param(
        6000,
        unit="ticks",
        doc="A static run that has not delivered everything ends here.",
        low=1,
        high=MAX_TICKS,
    )
    static_horizon: float = param(
        240.0,
        unit="s",
        doc="Range of the required delivery times (static model).",
        low=0.0,
        low_open=True,
        high=MAX_DURATION,
    )

    def __post_init__(self) -> None:
        check_part(self, "urgency")


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

    advertisement_loss: float = param(
        0.0,
        unit="",
        doc="Probability that a robot misses a tag's advertisement in a tick.",
        low=0.0,
        high=1.0,
        kernel=Kernel("advertisement_loss"),
    )
    status_delay: int = param(
        0,
        unit="ticks",
        doc="Ticks by which advertisements lag the tag's true state.",
        low=0,
        high=MAX_TICKS,
        kernel=Kernel("status_delay"),
    )
    detection_noise: float = param(
        0.0,
        unit="m",
        doc="Standard deviation of the camera's carrier position per axis.",
        low=0.0,
        high=MAX_LENGTH,
        kernel=Kernel("detection_noise"),
    )
    speed_variation: float = param(
        0.0,
        unit="",
        doc="Relative standard deviation of each robot's speed.",
        low=0.0,
        high=1.0,
        kernel=Kernel("speed_variation"),
    )
    breakdown: float = param(
        0.0,
        unit="",
        doc="Probability per robot per tick of breaking down for good.",
        low=0.0,
        high=1.0,
        kernel=Kernel("breakdown"),
    )

    def __post_init__(self) -> None:
        check_part(self, "realism")
        if self.advertisement_loss == 1.0:
            msg = (
                "realism.advertisement_loss: 1.0 is not a number in [0, 1) (no tag would be heard)"
            )
            raise ConfigError(msg)

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
