"""A virtual radio: simulated tags advertising to one receiver, deterministic and clock-free.

Each ``SimTag`` advertises its payload every ``interval`` seconds (BLE's
100-1000 ms range, 250 ms by default) at its own phase, on the microsecond
grid of ``tag/advertising.py`` that the simulator's radio channel uses too
(a tag of the same phase and interval is heard at the same moments in a
simulated run and by this scanner). An advert is heard
when the tag is within ``radio_range`` and survives the ``loss`` draw (from
the scanner's seeded ``numpy.random.Generator``, one draw per advert in time
order, so the result does not depend on how time is chopped into
``advance`` calls); it arrives ``delay`` seconds after it was sent, with an
RSSI from a log-distance path loss. ``changes_only`` mimics real stacks'
duplicate filtering (BlueZ's default): an address is reported again only
when its payload changed, so an unchanging tag ages out of ``states()``.

Time moves only when told: ``advance(now)`` delivers everything due by
``now``; ``poll()`` advances to the injected clock (for the CLI).
"""

from __future__ import annotations

import heapq
import math
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np

from swarmtag.errors import ConfigError
from swarmtag.tag.advertising import advert_times, microseconds, phase_microseconds
from swarmtag.tag.backends.base import DEFAULT_MAX_AGE, Scanner, check_seconds
from swarmtag.tag.codec import TagState, encode_manufacturer_data
from swarmtag.tag.status import TagStatus

__all__ = ["DEFAULT_INTERVAL", "SimScanner", "SimTag", "bench_tags", "rssi_at"]

DEFAULT_INTERVAL = 0.25
"""Seconds between two adverts of one tag."""
RSSI_AT_1M = -59
"""dBm heard at one metre (a typical BLE beacon's calibrated power)."""


def rssi_at(distance: float) -> int:
    """Log-distance path loss, exponent 2 (free space): ``-59 - 20 log10(d)`` dBm, d >= 0.1 m."""
    return round(RSSI_AT_1M - 20.0 * math.log10(max(distance, 0.1)))


@dataclass(frozen=True, slots=True)
class SimTag:
    """One simulated tag: its address, what it advertises and how far it is (metres).

    ``phase`` (seconds, below the interval; whole microseconds count) is when
    its first advert goes out after the scanner starts; ``None`` draws it
    from the scanner's generator, as a fraction of the interval (as the
    simulator draws its tags' phases).
    """

    address: str
    state: TagState
    distance: float = 1.0
    phase: float | None = None


def bench_tags() -> list[SimTag]:
    """Three tags on a bench, 1-4 m away: what ``swarmtag tag scan --backend sim`` hears."""
    states = [(9, TagStatus.AWAITING_PICKUP, 2, 12), (3, TagStatus.IDLE, 0, 7)]
    states.append((5, TagStatus.PICKED_UP, 1, 21))
    return [
        SimTag(
            f"SIM:00:00:00:00:{marker:02X}",
            TagState(urgency=urgency, status=status, destination=destination, marker=marker),
            distance=1.0 + i * 1.5,
        )
        for i, (urgency, status, destination, marker) in enumerate(states)
    ]


class SimScanner(Scanner):
    """A scanner hearing simulated tags; deterministic for a given generator and call sequence."""

    name = "sim"

    def __init__(
        self,
        *,
        tags: Sequence[SimTag] = (),
        interval: float = DEFAULT_INTERVAL,
        radio_range: float = 10.0,
        loss: float = 0.0,
        delay: float = 0.0,
        changes_only: bool = False,
        rng: np.random.Generator | None = None,
        max_age: float = DEFAULT_MAX_AGE,
        clock: Callable[[], float] = time.monotonic,
    ) -> None:
        super().__init__(max_age=max_age, clock=clock)
        self.interval = check_seconds("interval", interval, low=0.1, high=1.0)
        self.radio_range = check_seconds("radio_range", radio_range, low=0.0, high=1e6)
        self.loss = check_seconds("loss", loss, low=0.0, high=1.0)
        self.delay = check_seconds("delay", delay, low=0.0, high=60.0)
        self.changes_only = bool(changes_only)
        self._rng = np.random.default_rng(0) if rng is None else rng
        if not isinstance(self._rng, np.random.Generator):
            raise ConfigError(f"rng: expected a numpy.random.Generator, got {rng!r}")
        self._tags: dict[str, SimTag] = {}
        self._interval_us = microseconds(self.interval)
        self._phase: dict[str, int] = {}
        """Each tag's phase in microseconds after the start."""
        for tag in tags:
            self.add(tag)
        self._since: float | None = None
        self._origin = 0.0
        self._pending: list[tuple[float, int, str, bytes, int]] = []
        self._sent = 0
        self._reported: dict[str, bytes] = {}
        self.sent = 0
        self.lost = 0
        self.filtered = 0

    def add(self, tag: SimTag) -> None:
        """Put ``tag`` in the room (replacing a tag of that address, keeping its phase)."""
        if not isinstance(tag, SimTag):
            raise ConfigError(f"tags: expected SimTag objects, got {type(tag).__name__}")
        check_seconds(f"{tag.address}: distance", tag.distance, low=0.0, high=1e6)
        if tag.address not in self._phase:
            if tag.phase is None:
                phase = phase_microseconds(self._rng.random(), self._interval_us)
            else:
                given = check_seconds(f"{tag.address}: phase", tag.phase, high=self.interval)
                phase = min(microseconds(given), self._interval_us - 1)
            self._phase[tag.address] = phase
        self._tags[tag.address] = tag

    def set_state(self, address: str, state: TagState) -> None:
        """Change what the tag at ``address`` advertises from now on (an accepted write)."""
        if address not in self._tags:
            raise ConfigError(f"address: no simulated tag {address!r}")
        self.add(SimTag(address, state, self._tags[address].distance))

    def start(self) -> None:
        """Switch the radio on at the clock's time: tags' first adverts follow their phases."""
        if self._since is None:
            self._since = self._clock()
            self._origin = self._since

    def stop(self) -> None:
        """Switch the radio off: adverts still in flight are lost."""
        self._since = None
        self._pending.clear()

    def poll(self) -> None:
        """Advance to the injected clock's time."""
        self.advance(self._clock())

    def advance(self, now: float) -> int:
        """Send the adverts due in (last call, ``now``]; deliver those arrived; how many."""
        if self._since is None or now <= self._since:
            return 0
        adverts = sorted(
            (sent, index, address)
            for index, address in enumerate(self._tags)
            for sent in self._times(address, self._since, now)
        )
        for sent, _index, address in adverts:
            self._send(sent, address)
        self._since = now
        arrived = 0
        while self._pending and self._pending[0][0] <= now:
            at, _order, address, payload, rssi = heapq.heappop(self._pending)
            if self.changes_only and self._reported.get(address) == payload:
                self.filtered += 1
                continue
            self._reported[address] = payload
            self._receive(address, {0xFFFF: payload}, rssi, seen_at=at)
            arrived += 1
        return arrived

    def _times(self, address: str, after: float, until: float) -> list[float]:
        """Send times of ``address`` in (after, until]: origin + phase + k * interval, k >= 0."""
        window = microseconds(after - self._origin), microseconds(until - self._origin)
        sent = advert_times(self._phase[address], self._interval_us, *window)
        return [self._origin + at / 1e6 for at in sent]

    def _send(self, sent: float, address: str) -> None:
        tag = self._tags[address]
        self.sent += 1
        heard = self._rng.random() >= self.loss  # drawn for every advert: chunking-independent
        if not heard or tag.distance > self.radio_range:
            self.lost += 1
            return
        payload = encode_manufacturer_data(tag.state)[0xFFFF]
        self._sent += 1
        heapq.heappush(
            self._pending, (sent + self.delay, self._sent, address, payload, rssi_at(tag.distance))
        )
