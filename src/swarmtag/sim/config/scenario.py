"""The simulation scenario: typed, frozen, validated configuration (SPEC §4.1, §4.3).

A ``Scenario`` says everything about the world a run happens in, except the
policy and the seed: arena and zones, bodies, motion, behaviour timings,
urgency model, scheduled re-prioritisations and the optional realism. Build
it from keywords, ``Scenario.default(robots, carriers)``, a mapping
(``from_mapping``) or a TOML file (``from_toml``). Bad values raise
``ConfigError`` naming the field and the allowed range.

Larger swarms: unless an ``arena`` is given, its side and both zone widths
scale with ``(carriers / 7) ** arena_scaling`` (never below 1); the default
0.5 keeps carrier density (carriers per square metre of arena and of
pick-up area) that of the 3 / 7 lab set-up.
"""

from __future__ import annotations

import math
import os
from collections.abc import Mapping
from dataclasses import dataclass, field, fields
from typing import Any, Final

from swarmtag._checks import check_choice, check_int, check_number
from swarmtag.errors import ConfigError
from swarmtag.sim.config.mapping import load_toml, scenario_fields, scenario_to_mapping
from swarmtag.sim.config.parts import (
    MAX_LENGTH,
    MAX_TICKS,
    Arena,
    Bodies,
    Motion,
    Realism,
    Reprioritisation,
    Timing,
    UrgencyModel,
    Walk,
)
from swarmtag.sim.config.sensors import PERCEPTION_MODELS, Camera, Radio
from swarmtag.sim.config.warehouse import Warehouse, floor_of

__all__ = [
    "MAX_CARRIERS",
    "MAX_ROBOTS",
    "MAX_TICK",
    "MIN_TICK",
    "PARTS",
    "PERCEPTION_SCALINGS",
    "TIME_UNITS",
    "Scenario",
]

MAX_CARRIERS: Final = 256
"""Marker ids are one byte on the wire (SPEC §2.1): carriers are numbered 0-255."""
MAX_ROBOTS: Final = 10**7
"""Most robots per run: memory, not the kernel, is the real limit (checked before a run)."""
MIN_TICK: Final = 1e-6
"""Shortest tick in seconds: advertising phases live on an integer-microsecond grid."""
MAX_TICK: Final = 3600.0
"""Longest tick in seconds."""
_TIMING_FIELDS: Final = ("dock", "lift", "release", "pursuit_timeout", "cooldown")
TIME_UNITS: Final = ("tick", "s")
PERCEPTION_SCALINGS: Final = ("fixed", "arena")
"""``Scenario.perception_scaling``: the camera keeps its range, or it grows with the arena."""
PARTS: Final[tuple[tuple[str, type], ...]] = (
    ("arena", Arena),
    ("bodies", Bodies),
    ("motion", Motion),
    ("walk", Walk),
    ("radio", Radio),
    ("camera", Camera),
    ("timing", Timing),
    ("urgency", UrgencyModel),
    ("realism", Realism),
)
"""The scenario's parts (each declared with the parameter schema), by their TOML name."""
"""``Scenario.time_unit``: event-log times in ticks, or in seconds of robot time."""


def _grid_capacity(width: float, height: float, body: float, pitch: float) -> int:
    """How many bodies of size ``body`` fit on a grid of ``pitch`` in a ``width x height`` box."""
    if width < body or height < body:
        return 0
    return (math.floor((width - body) / pitch) + 1) * (math.floor((height - body) / pitch) + 1)


@dataclass(frozen=True, slots=True)
class Scenario:
    """Everything about the simulated world except policy and seed.

    ``ticks`` is the run length T of the growing model; static runs end when
    every carrier is delivered or at ``urgency.static_time_limit``. ``arena``
    defaults to the lab arena scaled for ``carriers`` by the exponent
    ``arena_scaling`` (see the module docs).
    ``perception`` is ``"disc"`` (one ``detection_radius``) or ``"split"``
    (``radio`` and ``camera``, SPEC §4.2a); ``perception_scaling`` whether
    the camera's range grows with the arena (``perception_factor``);
    ``time_unit`` is the unit of the
    event logs' times (``"tick"``, or ``"s"``: ticks times ``tick``).
    The field defaults are the base model (the simulator before profiles);
    ``Scenario.default`` starts from a profile (``swarmtag.sim.config.profiles``).

    >>> s = Scenario()
    >>> s.robots, s.carriers, s.arena.size, s.tick, s.run_ticks
    (3, 7, 3.75, 0.1, 3000)
    >>> Scenario(robots=0)
    Traceback (most recent call last):
    ...
    swarmtag.errors.ConfigError: robots: 0 is not an integer in 1-10000000
    """

    robots: int = 3
    carriers: int = 7
    ticks: int = 3000
    tick: float = 0.1
    detection_radius: float = 1.0
    perception: str = "disc"
    time_unit: str = "tick"
    arena_scaling: float = 0.5
    perception_scaling: str = "fixed"
    arena: Arena | None = None
    bodies: Bodies = field(default_factory=Bodies)
    motion: Motion = field(default_factory=Motion)
    walk: Walk = field(default_factory=Walk)
    radio: Radio = field(default_factory=Radio)
    camera: Camera = field(default_factory=Camera)
    timing: Timing = field(default_factory=Timing)
    urgency: UrgencyModel = field(default_factory=UrgencyModel)
    realism: Realism = field(default_factory=Realism)
    reprioritisations: tuple[Reprioritisation, ...] = ()
    warehouse: Warehouse | None = None

    def __post_init__(self) -> None:
        robots = check_int("robots", self.robots, low=1, high=MAX_ROBOTS)
        object.__setattr__(self, "robots", robots)
        # a warehouse's carriers are its orders, allocated below from its part (a given count,
        # e.g. from its own mapping, is replaced): only the lab arena's are marker ids
        floor = self.warehouse is not None
        carriers = check_int("carriers", self.carriers, low=1, high=None if floor else MAX_CARRIERS)
        object.__setattr__(self, "carriers", carriers)
        object.__setattr__(self, "ticks", check_int("ticks", self.ticks, low=1, high=MAX_TICKS))
        tick = check_number("tick", self.tick, low=MIN_TICK, high=MAX_TICK)
        object.__setattr__(self, "tick", tick)
        radius = check_number(
            "detection_radius", self.detection_radius, low=0.0, low_open=True, high=MAX_LENGTH
        )
        object.__setattr__(self, "detection_radius", radius)
        perception = check_choice("perception", self.perception, PERCEPTION_MODELS)
        object.__setattr__(self, "perception", perception)
        object.__setattr__(self, "time_unit", check_choice("time_unit", self.time_unit, TIME_UNITS))
        scaling = check_number("arena_scaling", self.arena_scaling, low=0.0, high=1.0)
        object.__setattr__(self, "arena_scaling", scaling)
        grows = check_choice("perception_scaling", self.perception_scaling, PERCEPTION_SCALINGS)
        object.__setattr__(self, "perception_scaling", grows)
        if self.arena is None:
            object.__setattr__(self, "arena", Arena.scaled(carriers, scaling))
        for name, kind in PARTS:
            part: object = getattr(self, name)
            if not isinstance(part, kind):
                msg = f"{name}: {part!r} is not a {kind.__name__}"
                raise ConfigError(msg)
        events = tuple(self.reprioritisations)
        for item in events:
            event: object = item
            if not isinstance(event, Reprioritisation):
                msg = f"reprioritisations: {event!r} is not a Reprioritisation"
                raise ConfigError(msg)
        object.__setattr__(self, "reprioritisations", events)
        if self.perception_scaling == "arena" and self.warehouse is not None:
            msg = "perception_scaling: 'arena' scales the camera with the lab arena, not a floor"
            raise ConfigError(msg)
        if self.radio.search and perception != "split":
            msg = "radio.search: BLE-led search needs perception = 'split' (radio and camera apart)"
            raise ConfigError(msg)
        if self.camera.look_around > 0 and (perception != "split" or self.radio.search):
            msg = (
                "camera.look_around: a look round before choosing needs perception = 'split' "
                "and no radio.search (a seeker chooses by its radio)"
            )
            raise ConfigError(msg)
        if self.warehouse is not None:
            self._order_capacity()
        self._check_durations()
        self._check_geometry()
        self._check_events()

    @classmethod
    def default(cls, robots: int = 3, carriers: int = 7, *, profile: str = "paper-sim") -> Scenario:
        """The default world for ``robots`` / ``carriers``: a profile (SPEC §4.6), arena scaled.

        ``profile`` is a shipped profile's name or a profile file; the field
        defaults of ``Scenario()`` are the ``base`` profile.
        """
        from swarmtag.sim.config.profiles import load_profile  # noqa: PLC0415 - profiles build scenarios

        return load_profile(profile).scenario({"robots": robots, "carriers": carriers})

    @classmethod
    def from_mapping(
        cls, data: Mapping[str, Any], overrides: Mapping[str, Any] | None = None
    ) -> Scenario:
        """A scenario from a mapping (TOML layout), with ``overrides`` merged on top.

        Overrides may nest or use dotted keys; unknown keys are errors.

        >>> s = Scenario.from_mapping({"carriers": 28}, {"timing.dock": 2.0})
        >>> round(s.area.size, 6), s.timing.dock
        (7.5, 2.0)
        >>> Scenario.from_mapping({"arena": {"sise": 4.0}})
        Traceback (most recent call last):
        ...
        swarmtag.errors.ConfigError: arena.sise: unknown key; [arena] has keys ...
        """
        return cls(**scenario_fields(data, overrides))

    @classmethod
    def from_toml(
        cls, path: str | os.PathLike[str], overrides: Mapping[str, Any] | None = None
    ) -> Scenario:
        """A scenario from a TOML file (the ``from_mapping`` layout), with ``overrides``."""
        data = load_toml(path)  # its errors name the file already
        try:
            return cls.from_mapping(data, overrides)
        except ConfigError as error:
            msg = f"{os.fspath(path)}: {error}"
            raise ConfigError(msg) from None

    def to_mapping(self) -> dict[str, Any]:
        """Plain nested values that ``from_mapping`` reads back into an equal scenario.

        >>> Scenario.from_mapping(Scenario().to_mapping()) == Scenario()
        True
        """
        return scenario_to_mapping({f.name: getattr(self, f.name) for f in fields(self)})

    def _check_durations(self) -> None:
        """Every duration in seconds must be at most ``MAX_TICKS`` ticks long at this tick."""
        durations = {
            **{f"timing.{name}": getattr(self.timing, name) for name in _TIMING_FIELDS},
            "motion.stuck_time": self.motion.stuck_time,
            "motion.sidestep_time": self.motion.sidestep_time,
            "walk.turn_interval": self.walk.turn_interval,
            "camera.memory": self.camera.memory,
            "radio.interval": self.radio.interval,
            "urgency.static_horizon": self.urgency.static_horizon,
        }
        for name, seconds in durations.items():
            if seconds / self.tick > MAX_TICKS:
                msg = (
                    f"{name}: {seconds:g} s is {seconds / self.tick:.3g} ticks of {self.tick:g} s;"
                    f" durations may be at most {MAX_TICKS:.0e} ticks (use a longer tick)"
                )
                raise ConfigError(msg)

    def perception_summary(self) -> str:
        """One line on how robots perceive carriers, for headers and reports.

        >>> Scenario().perception_summary()
        'disc perception, R = 1 m'
        >>> Scenario(perception="split").perception_summary()
        'camera 1 m (occlusion none, memory 0 s), radio 10 m every 0.25 s'
        """
        if self.perception == "disc":
            return f"disc perception, R = {self.detection_radius:g} m"
        camera, radio = self.camera, self.radio
        search = (
            f", BLE-led search (n = {radio.path_loss_exponent:g}, {radio.shadowing:g} dB)"
            if radio.search
            else ""
        )
        grown = (
            f" x {self.perception_factor:.3g} = {camera.range * self.perception_factor:.3g} m"
            if self.perception_scaling == "arena"
            else ""
        )
        return (
            f"camera {camera.range:g} m{grown} (occlusion {camera.occlusion}, memory"
            f" {camera.memory:g} s), radio {radio.range:g} m every {radio.interval:g} s{search}"
        )

    @property
    def perception_factor(self) -> float:
        """The camera's range and fade are multiplied by this: 1, or arena side over the lab's.

        With ``perception_scaling = "arena"`` the camera sees as far relative
        to its arena as in the 3.75 m lab (a different robot in every arena);
        ``"fixed"`` keeps a camera's range, as a real camera does.

        >>> Scenario(carriers=28, perception_scaling="arena").perception_factor
        2.0
        """
        if self.perception_scaling == "fixed":
            return 1.0
        return self.area.size / Arena().size

    @property
    def area(self) -> Arena:
        """The arena (never ``None`` after construction)."""
        assert self.arena is not None
        return self.arena

    @property
    def run_ticks(self) -> int:
        """Ticks a run lasts at most: ``ticks`` (growing) or the static time limit."""
        return self.ticks if self.urgency.model == "growing" else self.urgency.static_time_limit

    def _order_capacity(self) -> None:
        """A warehouse: check its part and pre-allocate its orders as the carriers."""
        given: object = self.warehouse
        if not isinstance(given, Warehouse):
            msg = f"warehouse: {given!r} is not a Warehouse"
            raise ConfigError(msg)
        if self.urgency.model != "growing":
            msg = (
                f"urgency.model: {self.urgency.model!r}; a warehouse's orders use the growing "
                "model (their urgency rises while they wait)"
            )
            raise ConfigError(msg)
        if self.reprioritisations:
            msg = (
                "reprioritisations: not available in a warehouse (its carriers are orders "
                "that arrive during the run); leave them out or use the lab arena"
            )
            raise ConfigError(msg)
        object.__setattr__(self, "carriers", given.order_capacity(self.ticks * self.tick))

    def _check_geometry(self) -> None:
        arena, bodies, motion = self.area, self.bodies, self.motion
        if self.warehouse is not None:
            self._check_motion()
            self.warehouse.check_floor(
                floor_of(self.warehouse),
                robots=self.robots,
                carrier_size=bodies.carrier_size,
                spacing=arena.carrier_spacing,
                largest_margin=max(bodies.robot_diameter, bodies.carrier_size) / 2,
                step=motion.speed * self.tick,
            )
            return
        self._check_motion()
        if arena.carrier_spacing < bodies.robot_diameter:
            msg = (
                f"arena.carrier_spacing: {arena.carrier_spacing!r} is less than the robot "
                f"diameter {bodies.robot_diameter!r}; a robot must fit between two carriers"
            )
            raise ConfigError(msg)
        largest = max(bodies.robot_diameter, bodies.carrier_size)
        if arena.dropoff_width < largest:
            msg = (
                f"arena.dropoff_width: {arena.dropoff_width!r} is smaller than a loaded robot "
                f"({largest!r}); a carrier must fit inside the drop-off area"
            )
            raise ConfigError(msg)
        pitch = bodies.carrier_size + arena.carrier_spacing
        room = _grid_capacity(arena.pickup_width, arena.size, bodies.carrier_size, pitch)
        if self.carriers > room:
            msg = (
                f"carriers: {self.carriers} do not fit in the pick-up area "
                f"({arena.pickup_width!r} x {arena.size!r} m holds at most {room} with spacing "
                f"{arena.carrier_spacing!r}); widen arena.pickup_width or use fewer carriers"
            )
            raise ConfigError(msg)
        room = _grid_capacity(
            arena.dropoff_width, arena.size, bodies.robot_diameter, bodies.robot_diameter
        )
        if self.robots > room:
            msg = (
                f"robots: {self.robots} do not fit in the drop-off area where they start "
                f"(at most {room}); widen arena.dropoff_width or use fewer robots"
            )
            raise ConfigError(msg)

    def _check_motion(self) -> None:
        """The predock stand-off clears the robot, and a tick's step is under its radius."""
        motion, radius = self.motion, self.bodies.robot_diameter / 2
        if motion.predock_distance <= radius:
            msg = (
                f"motion.predock_distance: {motion.predock_distance!r} is not more than the "
                f"robot radius {radius!r}; the robot must stand clear of the carrier face"
            )
            raise ConfigError(msg)
        if motion.speed * self.tick > radius:
            msg = (
                f"motion.speed: {motion.speed!r} m/s moves more than the robot radius per tick "
                f"({self.tick!r} s); use a shorter tick or a lower speed"
            )
            raise ConfigError(msg)

    def _check_events(self) -> None:
        if self.realism.status_delay > self.run_ticks:
            msg = (
                f"realism.status_delay: {self.realism.status_delay} ticks is longer than the run "
                f"(0-{self.run_ticks})"
            )
            raise ConfigError(msg)
        for event in self.reprioritisations:
            if event.carrier >= self.carriers:
                msg = (
                    f"reprioritisations.carrier: {event.carrier} is not a carrier of this "
                    f"scenario (0-{self.carriers - 1})"
                )
                raise ConfigError(msg)
            if event.tick > self.run_ticks:
                msg = (
                    f"reprioritisations.tick: {event.tick} is after the end of the run "
                    f"(1-{self.run_ticks})"
                )
                raise ConfigError(msg)
