"""A scanner's sightings as the robot-I/O ``tag_states`` sensor: the robot's BLE cache.

A scanner (``swarmtag.tag.backends``) keeps the latest fresh ``Sighting`` of
each carrier it hears, in seconds of its clock, and drops one not heard for
``max_age`` seconds. A controller reads ``TagStates``: arrays over the site's
carriers by marker id, status -1 for a tag never heard, the age in control
ticks. ``tag_states`` converts one set of sightings; ``TagCache`` also
remembers, as the simulated robot's cache does (``known_status``,
``heard_tick``): a tag once heard stays known with its last state while its
age grows, even after the scanner dropped it, until it is heard again. A
controller that distrusts old states reads ``age``.

With a ``Ranging`` (BLE-led search, docs/simulator.md) the cache also turns
each new sighting's RSSI into a distance with the log-distance path-loss
model and keeps a running estimate per carrier (``TagStates.distance``), as
the simulated robot does.

The age of a sighting heard at ``seen_at`` is ``floor((now - seen_at) /
tick)`` ticks (0 in the tick it was heard, as in the simulator). Markers at
or above ``carriers`` are not the site's carriers: they are left out (the
cache notes them in ``ignored``).
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping
from dataclasses import dataclass

import numpy as np

from swarmtag._checks import check_int, check_number
from swarmtag.errors import ConfigError
from swarmtag.robot.io import TagStates
from swarmtag.tag.backends.base import Scanner, Sighting

__all__ = ["Ranging", "TagCache", "tag_states"]

_MAX_CARRIERS = 256
"""Marker ids are one byte: a site has at most 256 carriers with tags."""


@dataclass(frozen=True)
class Ranging:
    """How a robot turns a tag's RSSI (dBm) into a distance (m): path loss, then smoothing.

    ``rssi_at_1m`` is the site's tags' mean RSSI at 1 m (measure it: it
    depends on the tag and the receiver; the default is the indoor mean of
    Strzoda, Grochla and Polys, MSWiM 2022); ``path_loss_exponent`` and
    ``smoothing`` as ``radio.path_loss_exponent`` and ``radio.smoothing``.

    >>> Ranging().distance(-65.5), round(Ranging().distance(-85.5), 6)
    (1.0, 10.0)
    """

    rssi_at_1m: float = -65.5
    path_loss_exponent: float = 2.0
    smoothing: float = 0.25

    def __post_init__(self) -> None:
        check_number("rssi_at_1m", self.rssi_at_1m, low=-150.0, high=20.0)
        check_number("path_loss_exponent", self.path_loss_exponent, low=1.0, high=6.0)
        check_number("smoothing", self.smoothing, low=0.0, low_open=True, high=1.0)

    def distance(self, rssi: float) -> float:
        """The distance an RSSI implies: ``10 ** ((rssi_at_1m - rssi) / (10 n))``."""
        return float(10.0 ** ((self.rssi_at_1m - rssi) / (10.0 * self.path_loss_exponent)))

    def update(self, estimate: float | None, rssi: float) -> float:
        """A running estimate after one more sighting (the first one starts it)."""
        sample = self.distance(rssi)
        return sample if estimate is None else estimate + self.smoothing * (sample - estimate)


def _checked(carriers: object, tick: object) -> tuple[int, float]:
    count = check_int("carriers", carriers, low=1, high=_MAX_CARRIERS)
    seconds = check_number("tick", tick, low=0.0, low_open=True, high=3600.0)
    return count, seconds


def _sightings(sightings: object) -> list[Sighting]:
    """``sightings`` (a ``Scanner.states()`` mapping or an iterable) as a checked list."""
    if not isinstance(sightings, Iterable):
        kind = type(sightings).__name__
        raise ConfigError(f"sightings: expected Scanner.states() or Sighting objects, got {kind}")
    found = list(sightings.values() if isinstance(sightings, Mapping) else sightings)
    for sighting in found:
        if not isinstance(sighting, Sighting):
            raise ConfigError(
                f"sightings: expected Sighting objects, got {type(sighting).__name__}"
            )
    return found


def tag_states(
    sightings: Mapping[int, Sighting] | Iterable[Sighting],
    *,
    carriers: int,
    now: float,
    tick: float,
) -> TagStates:
    """``TagStates`` over ``carriers`` markers from ``sightings`` (e.g. ``Scanner.states()``).

    >>> from swarmtag.tag import TagState, TagStatus
    >>> heard = Sighting(1, TagState(7, TagStatus.AWAITING_PICKUP, 3, 1), -60, 9.75, "AA")
    >>> s = tag_states({1: heard}, carriers=3, now=10.0, tick=0.1)
    >>> s.status.tolist(), s.urgency.tolist(), s.age.tolist()
    ([-1, 1, -1], [0, 7, 0], [-1, 2, -1])
    """
    count, seconds = _checked(carriers, tick)
    moment = check_number("now", now)
    status = np.full(count, -1, dtype=np.int8)
    urgency = np.zeros(count, dtype=np.int8)
    age = np.full(count, -1, dtype=np.int64)
    for sighting in _sightings(sightings):
        if sighting.marker < count:
            status[sighting.marker] = int(sighting.state.status)
            urgency[sighting.marker] = sighting.state.urgency
            age[sighting.marker] = max(0, math.floor((moment - sighting.seen_at) / seconds))
    return TagStates(status=status, urgency=urgency, age=age)


class TagCache:
    """The robot's memory of every carrier's last heard state, fed from a scanner.

    >>> from swarmtag.tag.backends.fake import FakeScanner
    >>> scanner = FakeScanner(clock=lambda: 5.0)
    >>> _ = scanner.feed("AA", {0xFFFF: bytes([7, 1, 3, 2])})
    >>> cache = TagCache(carriers=4, tick=0.1)
    >>> cache.read(scanner).status.tolist()
    [-1, -1, 1, -1]
    """

    def __init__(self, *, carriers: int, tick: float, ranging: Ranging | None = None) -> None:
        self.carriers, self.tick = _checked(carriers, tick)
        if ranging is not None and not isinstance(ranging, Ranging):
            raise ConfigError(f"ranging: expected a Ranging, got {type(ranging).__name__}")
        self.ranging = ranging
        self._held: dict[int, Sighting] = {}
        self._estimate: dict[int, float] = {}
        self._ignored: set[int] = set()

    @property
    def ignored(self) -> frozenset[int]:
        """Marker ids heard that are not the site's carriers (at or above ``carriers``)."""
        return frozenset(self._ignored)

    def update(self, sightings: Mapping[int, Sighting] | Iterable[Sighting]) -> int:
        """Remember ``sightings`` newer than what is held; how many were new."""
        kept = 0
        for sighting in _sightings(sightings):
            if sighting.marker >= self.carriers:
                self._ignored.add(sighting.marker)
                continue
            held = self._held.get(sighting.marker)
            if held is None or sighting.seen_at > held.seen_at:
                self._held[sighting.marker] = sighting
                if self.ranging is not None:
                    previous = self._estimate.get(sighting.marker)
                    self._estimate[sighting.marker] = self.ranging.update(previous, sighting.rssi)
                kept += 1
        return kept

    def states(self, now: float) -> TagStates:
        """The ``tag_states`` sensor at ``now`` (the scanner's clock), ranged with a ``Ranging``."""
        found = tag_states(self._held, carriers=self.carriers, now=now, tick=self.tick)
        if self.ranging is None:
            return found
        distance = np.full(self.carriers, np.nan)
        for marker, estimate in self._estimate.items():
            distance[marker] = estimate
        return TagStates(found.status, found.urgency, found.age, distance=distance)

    def read(self, scanner: Scanner) -> TagStates:
        """Catch up with ``scanner`` (poll, take its sightings) and return the sensor now."""
        if not isinstance(scanner, Scanner):
            raise ConfigError(f"scanner: expected a Scanner, got {type(scanner).__name__}")
        scanner.poll()
        self.update(scanner.states())
        return self.states(scanner.now())
