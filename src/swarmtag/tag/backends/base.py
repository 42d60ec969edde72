"""What every tag transport shares: the ``Scanner`` interface and the ``TagTable`` it keeps.

A robot's BLE library runs on its own (a thread, a simulated radio, a test's
hand) and hears many advertisements; the controller only wants the latest
state of each carrier in range, with how old it is and how loud it was
(SPEC §2.5, §7). ``TagTable`` is that bookkeeping as a pure object (times are
arguments, never read from a clock); ``Scanner`` wraps it with a lock, an
injected clock and the ``ScanFilter`` counters, so a backend only has to call
``_receive`` with what its radio heard.
"""

from __future__ import annotations

import math
import re
import threading
import time
from abc import ABC, abstractmethod
from collections import Counter
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from types import TracebackType
from typing import ClassVar, Final, Self

from swarmtag.errors import ConfigError, RadioError
from swarmtag.tag.codec import TagState
from swarmtag.tag.scan import ScanFilter

__all__ = [
    "DEFAULT_MAX_AGE",
    "Running",
    "Scanner",
    "Sighting",
    "TagTable",
    "check_adapter",
    "check_address",
    "check_seconds",
]

DEFAULT_MAX_AGE: Final = 5.0
"""Seconds after which a carrier not heard again is dropped: 20 adverts at the default 250 ms."""


def check_seconds(name: str, value: object, *, low: float = 0.0, high: float = 3600.0) -> float:
    """``value`` as a finite float in ``[low, high]``, else ``ConfigError`` naming ``name``."""
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise ConfigError(f"{name}: expected a number of seconds, got {type(value).__name__}")
    seconds = float(value)
    if not (math.isfinite(seconds) and low <= seconds <= high):
        raise ConfigError(f"{name}: {value!r} is not a number in {low:g}-{high:g}")
    return seconds


def check_address(address: object) -> str:
    """``address`` if it is a Bluetooth address (``AA:BB:CC:DD:EE:FF``) or a macOS device UUID.

    >>> check_address("c4:7f:0e:12:34:56")
    'C4:7F:0E:12:34:56'
    """
    if isinstance(address, str):
        if re.fullmatch(r"[0-9A-Fa-f]{2}(:[0-9A-Fa-f]{2}){5}", address):
            return address.upper()
        if re.fullmatch(r"[0-9A-Fa-f]{8}(-[0-9A-Fa-f]{4}){3}-[0-9A-Fa-f]{12}", address):
            return address.upper()  # CoreBluetooth names devices by UUID, not address
    shown = repr(address)[:60]
    raise ConfigError(
        f"address: {shown} is not a Bluetooth address such as AA:BB:CC:DD:EE:FF (or, on macOS, "
        "a device UUID); 'swarmtag tag scan' lists the tags' addresses"
    )


def check_adapter(adapter: object) -> str | None:
    """``adapter`` if it names a BlueZ adapter (``hci0``, ``hci1``, ...) or is ``None`` (default).

    >>> check_adapter("hci1")
    'hci1'
    """
    if adapter is None:
        return None
    if not isinstance(adapter, str) or not re.fullmatch(r"hci[0-9]{1,3}", adapter):
        shown = repr(adapter)[:40]
        raise ConfigError(
            f"adapter: {shown} is not a BlueZ adapter name such as hci0 or hci1 "
            "('bluetoothctl list' shows the adapters)"
        )
    return adapter


@dataclass(frozen=True, slots=True)
class Sighting:
    """One carrier's latest advertisement: its state, RSSI (dBm), when and from which address.

    ``seen_at`` is in the scanner's clock (``time.monotonic`` unless injected).
    """

    marker: int
    state: TagState
    rssi: int
    seen_at: float
    address: str


class TagTable:
    """Keep the latest sighting per carrier (marker id) and age out stale ones; pure.

    A sighting older than the one held is ignored (a delayed advert must not
    undo a newer one). ``latest(now)`` drops every sighting older than
    ``max_age`` seconds at ``now`` and returns the rest by marker.

    >>> from swarmtag.tag import TagStatus
    >>> state = TagState(urgency=7, status=TagStatus.AWAITING_PICKUP, destination=3, marker=12)
    >>> table = TagTable(max_age=5.0)
    >>> table.update(Sighting(12, state, -60, seen_at=1.0, address="AA"))
    True
    >>> sorted(table.latest(now=4.0)), sorted(table.latest(now=6.5))
    ([12], [])
    """

    def __init__(self, *, max_age: float = DEFAULT_MAX_AGE) -> None:
        self.max_age = check_seconds("max_age", max_age, low=0.001, high=86400.0)
        self._latest: dict[int, Sighting] = {}

    def __len__(self) -> int:
        return len(self._latest)

    def update(self, sighting: Sighting) -> bool:
        """Hold ``sighting`` unless a newer one of that carrier is held; whether it was kept."""
        held = self._latest.get(sighting.marker)
        if held is not None and held.seen_at > sighting.seen_at:
            return False
        self._latest[sighting.marker] = sighting
        return True

    def prune(self, now: float) -> int:
        """Drop the sightings older than ``max_age`` at ``now``; how many were dropped."""
        stale = [m for m, s in self._latest.items() if now - s.seen_at > self.max_age]
        for marker in stale:
            del self._latest[marker]
        return len(stale)

    def latest(self, now: float) -> dict[int, Sighting]:
        """The fresh sightings at ``now``, by marker id, in marker order."""
        self.prune(now)
        return dict(sorted(self._latest.items()))


class Running(ABC):
    """Something started and stopped around a ``with`` block: scanners and tag servers."""

    @abstractmethod
    def start(self) -> None:
        """Begin (returns at once)."""

    @abstractmethod
    def stop(self) -> None:
        """End and release the radio."""

    def __enter__(self) -> Self:
        self.start()
        return self

    def __exit__(
        self,
        kind: type[BaseException] | None,
        value: BaseException | None,
        traceback: TracebackType | None,
    ) -> None:
        self.stop()


class Scanner(Running):
    """A running source of tag sightings; use as ``with open_scanner(...) as scanner:``.

    Subclasses implement ``start``/``stop`` and call ``_receive`` (from any
    thread) for every advertisement heard. ``states()`` is what the robot's
    controller reads: the latest sighting per carrier, stale ones aged out
    after ``max_age`` seconds of ``clock``. ``accepted``/``foreign``/``malformed``
    are the ``ScanFilter`` counters: a rising ``malformed`` means a broken tag.
    """

    name: ClassVar[str] = "scanner"

    def __init__(
        self, *, max_age: float = DEFAULT_MAX_AGE, clock: Callable[[], float] = time.monotonic
    ) -> None:
        if not callable(clock):
            raise ConfigError(f"clock: expected a function returning seconds, got {clock!r}")
        self._table = TagTable(max_age=max_age)
        self._filter = ScanFilter()
        self._clock = clock
        self._lock = threading.Lock()

    @abstractmethod
    def start(self) -> None:
        """Begin listening (returns at once; adverts arrive in the background or via ``poll``)."""

    @abstractmethod
    def stop(self) -> None:
        """Stop listening and release the radio; the sightings held so far stay readable."""

    def poll(self) -> None:
        """Catch up to the clock, for backends without a thread of their own (none by default)."""

    @property
    def failure(self) -> RadioError | None:
        """Why the radio gave up (``None`` while it works); the default backends never fail."""
        return None

    @property
    def max_age(self) -> float:
        """Seconds a sighting stays in ``states()`` without being heard again."""
        return self._table.max_age

    def now(self) -> float:
        """The scanner's clock, the time base of ``Sighting.seen_at``."""
        return self._clock()

    def states(self) -> dict[int, Sighting]:
        """The latest fresh sighting of each carrier in range, by marker id."""
        with self._lock:
            return self._table.latest(self._clock())

    @property
    def accepted(self) -> int:
        """Advertisements decoded as our tags."""
        return self._filter.accepted

    @property
    def foreign(self) -> int:
        """Advertisements of other devices (no 0xFFFF manufacturer data), ignored."""
        return self._filter.foreign

    @property
    def malformed(self) -> int:
        """Advertisements that claimed to be ours but could not be decoded."""
        return self._filter.malformed

    @property
    def errors(self) -> Counter[str]:
        """Malformed advertisements by error class name (a copy)."""
        with self._lock:
            return Counter(self._filter.errors)

    def _receive(
        self,
        address: str,
        manufacturer_data: Mapping[int, bytes] | bytes,
        rssi: int,
        *,
        seen_at: float | None = None,
    ) -> Sighting | None:
        """Decode one advertisement and hold it; ``None`` if foreign or malformed (counted)."""
        with self._lock:
            state = self._filter.feed(manufacturer_data)
            if state is None:
                return None
            when = self._clock() if seen_at is None else seen_at
            sighting = Sighting(state.marker, state, int(rssi), when, str(address))
            self._table.update(sighting)
            return sighting
