"""The perception parts of a scenario (SPEC §4.2, §4.2a): the robot's radio and its camera.

Two models of perception, chosen by ``Scenario.perception``:

- ``"split"`` (as on the robot): the BLE radio hears a tag's advertisement
  (urgency and status) within ``radio.range``, once per advertising
  ``radio.interval``; the 360° camera sees a carrier (its relative position,
  hence the distance ``d``) within ``camera.range``, optionally not through
  other carriers or robots (``camera.occlusion``), and optionally remembers
  where it saw carriers for ``camera.memory`` seconds. A carrier is a
  candidate only when its position is known from the camera (now or
  remembered) **and** it was last heard AWAITING_PICKUP.
- ``"disc"`` (the model before profiles, kept so old results reproduce):
  one ``detection_radius``; a carrier within it is both seen and heard,
  every tick.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Final

from swarmtag.errors import ConfigError
from swarmtag.sim.config.bearing import BEARING_PROFILES
from swarmtag.sim.config.parts import MAX_DURATION, MAX_LENGTH
from swarmtag.sim.config.schema import CHOICE_INDEX, MICROSECONDS, TICKS, Kernel, check_part, param

__all__ = ["OCCLUSION_MODELS", "PERCEPTION_MODELS", "Camera", "Radio"]

PERCEPTION_MODELS: Final = ("disc", "split")
"""``Scenario.perception``: one detection radius, or radio and camera apart."""
OCCLUSION_MODELS: Final = ("none", "carriers", "carriers+robots")
"""``camera.occlusion``: what blocks the camera's line of sight to a carrier."""


@dataclass(frozen=True, slots=True)
class Radio:
    """The robot's BLE receiver (split perception).

    ``range`` (m) is how far a tag's advertisement is heard (BLE reaches
    well beyond a lab arena); ``interval`` (s) is the tags' advertising
    interval: each tag advertises once per interval, at a phase of its own,
    so a robot's knowledge of a status can lag by up to one interval.
    Advertisement loss and status delay are in ``realism``.

    With ``search`` a robot also ranges every tag it hears by its signal
    strength (BLE-led search, docs/simulator.md): an advertisement's RSSI
    follows the log-distance path-loss model with exponent
    ``path_loss_exponent`` and log-normal shadowing of ``shadowing`` dB, so
    the distance it implies is the true one times ``10 ** (-X / (10 n))``,
    X ~ N(0, shadowing^2); a robot keeps a running estimate per tag
    (``smoothing``: the weight of each new distance). Defaults from indoor
    BLE advertisement measurements (Strzoda, Grochla and Polys, MSWiM 2022:
    mean RSSI at 1, 5, 10 and 16 m fits n = 2.03; standard deviations
    3.5-5.9 dB, mean 4.9).
    """

    range: float = param(
        10.0,
        unit="m",
        doc="How far a tag's advertisement is heard.",
        low=0.0,
        low_open=True,
        high=MAX_LENGTH,
        kernel=Kernel("radio_range"),
    )
    interval: float = param(
        0.25,
        unit="s",
        doc="The tags' advertising interval.",
        low=0.0,
        low_open=True,
        high=MAX_DURATION,
        kernel=Kernel("advert_us", MICROSECONDS),
    )

    search: bool = param(
        False,
        unit="",
        doc="BLE-led search: head for the best-scoring heard tag before the camera sees it.",
        kernel=Kernel("radio_search", controller=True),
    )
    path_loss_exponent: float = param(
        2.0,
        unit="",
        doc="n of the log-distance path-loss model that turns RSSI into distance.",
        low=1.0,
        high=6.0,
    )
    shadowing: float = param(
        5.0,
        unit="dB",
        doc="Standard deviation of an advertisement's RSSI about the path-loss model.",
        low=0.0,
        high=20.0,
    )
    smoothing: float = param(
        0.25,
        unit="",
        doc="Weight of a new RSSI distance in a robot's running estimate (1: latest only).",
        low=0.0,
        low_open=True,
        high=1.0,
        kernel=Kernel("rssi_smoothing", controller=True),
    )

    def __post_init__(self) -> None:
        check_part(self, "radio")


@dataclass(frozen=True, slots=True)
class Camera:
    """The robot's four perimeter cameras, 360° together (split perception).

    ``range`` (m, robot centre to carrier centre) is where a carrier's ArUco
    marker is read: with ``fade`` 0 (a hard disc) every carrier within it is
    seen; with ``fade`` > 0 it is the 50 % detection distance of a linear
    ramp ``fade`` wide (every carrier seen within ``range - fade / 2``, none
    beyond ``range + fade / 2``; each robot-carrier pair draws anew every
    tick), the shape the camera range study measures
    (docs/perception.md). ``occlusion`` says what blocks the line of sight
    between the centres (``"none"``, other ``"carriers"``' footprints, or
    ``"carriers+robots"``); ``memory`` (s) is how long a robot remembers
    where it last saw a carrier (0: only what it sees now). ``bearing`` names
    how the reach varies around the robot (``swarmtag.sim.config.bearing``):
    ``"uniform"`` sees alike all round, ``"dots"`` as the DOTS robot's four
    cameras do, blind around ±73° and short behind. With ``look_around``
    > 0 (s) a walking robot that sees a candidate does not choose at once:
    it stands and turns in place (counter-clockwise at ``motion.turn_rate``)
    for that long so that its cameras sweep round, then chooses among every
    carrier it saw meanwhile. ``drift`` (m per square root of a metre) is
    the robot's odometry error: its estimate of where it is wanders off
    by a random walk whose variance grows with the distance it drives, so
    a remembered position (kept in the robot's own frame) blurs as the robot
    moves on. With
    ``Scenario.perception_scaling = "arena"`` the kernel multiplies range
    and fade by ``Scenario.perception_factor``.
    """

    range: float = param(
        1.0,
        unit="m",
        doc="Robot centre to carrier centre within which a marker is read.",
        low=0.0,
        low_open=True,
        high=MAX_LENGTH,
    )
    occlusion: str = param(
        "none",
        unit="",
        doc="What blocks the camera's line of sight.",
        choices=OCCLUSION_MODELS,
        kernel=Kernel("occlusion", CHOICE_INDEX),
    )
    memory: float = param(
        0.0,
        unit="s",
        doc="How long a robot remembers where it saw a carrier (0: not at all).",
        low=0.0,
        high=MAX_DURATION,
        kernel=Kernel("memory_ticks", TICKS),
    )
    fade: float = param(
        0.0,
        unit="m",
        doc="Width of the detection ramp centred on range (0: a hard disc).",
        low=0.0,
        high=MAX_LENGTH,
    )
    drift: float = param(
        0.0,
        unit="m/√m",
        doc="Odometry error of remembered positions per axis after 1 m driven (0: exact).",
        low=0.0,
        high=1.0,
        kernel=Kernel("odometry_drift"),
    )
    look_around: float = param(
        0.0,
        unit="s",
        doc="On a first sighting a robot stands and turns this long, then chooses (0: at once).",
        low=0.0,
        high=MAX_DURATION,
    )
    bearing: str = param(
        "uniform",
        unit="",
        doc="How the reach varies with bearing: alike all round, or a measured rig's profile.",
        choices=tuple(BEARING_PROFILES),
    )

    def __post_init__(self) -> None:
        check_part(self, "camera")
        if self.fade > 2 * self.range:
            msg = (
                f"camera.fade: {self.fade!r} is more than twice camera.range {self.range!r} "
                "(the ramp would start before the robot)"
            )
            raise ConfigError(msg)
