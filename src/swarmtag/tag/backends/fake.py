"""An in-memory scanner that hears exactly what a test feeds it: no radio, no thread.

Tests of anything that reads tag states (the CLI, a controller) feed
advertisements by hand with ``feed`` and read ``states()`` as from a real
radio; ``fail`` makes it report a radio failure, as an adapter that gave up.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Mapping

from swarmtag.errors import RadioError
from swarmtag.tag.backends.base import DEFAULT_MAX_AGE, Scanner, Sighting

__all__ = ["FakeScanner"]


class FakeScanner(Scanner):
    r"""A scanner fed by hand; ``running`` says whether it was started and not stopped.

    >>> scanner = FakeScanner(clock=lambda: 10.0)
    >>> with scanner:
    ...     scanner.feed("AA:BB", {0xFFFF: b"\x07\x01\x03\x0c"}, rssi=-61).marker
    ...     scanner.feed("CC:DD", {0x004C: b"\x02\x15"}) is None
    12
    True
    >>> [(s.marker, s.rssi) for s in scanner.states().values()], scanner.foreign
    ([(12, -61)], 1)
    """

    name = "fake"

    def __init__(
        self, *, max_age: float = DEFAULT_MAX_AGE, clock: Callable[[], float] = time.monotonic
    ) -> None:
        super().__init__(max_age=max_age, clock=clock)
        self.running = False
        self.starts = 0
        self._failure: RadioError | None = None

    def start(self) -> None:
        """Mark the scanner running."""
        self.running = True
        self.starts += 1

    def stop(self) -> None:
        """Mark the scanner stopped (what was fed stays readable)."""
        self.running = False

    def feed(
        self,
        address: str,
        manufacturer_data: Mapping[int, bytes] | bytes,
        rssi: int = -60,
        *,
        seen_at: float | None = None,
    ) -> Sighting | None:
        """Hear one advertisement now (or at ``seen_at``); the sighting, or ``None`` if not ours."""
        return self._receive(address, manufacturer_data, rssi, seen_at=seen_at)

    def fail(self, error: RadioError) -> None:
        """Report ``error`` as the radio's failure from now on."""
        self._failure = error

    @property
    def failure(self) -> RadioError | None:
        """The failure set by ``fail``, if any."""
        return self._failure
