"""The console's ``--scan`` source: real tags heard by a BLE scanner, written over GATT.

``ScanSource`` reads a ``swarmtag.tag.backends.Scanner`` (bleak's on a real
adapter; the simulated bench radio or a fake one in tests): every carrier
heard within the scanner's ``max_age``, with its state, RSSI, address and
how long ago it was heard. Real tags have no floor position, so the page
shows the table and the KPIs a scan can measure (tags in range by status,
urgencies, adverts heard, foreign and malformed ones) and says there is no
floor.

``ScanDesk`` writes through ``swarmtag.tag.backends.bleak_writer.BleakTagWriter``,
the path of ``swarmtag tag write``: connect to the tag's address, read its
state, reserve the operator's counter in the counter file, sign with the
operator key, write with response, read back. Until the tag advertises its
new state, the table shows the state it read back after the write.

``bench_radio`` is the hidden ``--backend sim`` of ``swarmtag console --scan``:
the three bench tags of ``swarmtag tag scan --backend sim`` on the simulated
radio, each a ``SoftwareTag`` reached through the loopback GATT client, so
the whole path runs without a radio.
"""

from __future__ import annotations

import threading
import time
from collections.abc import Callable
from typing import Any, Final

from swarmtag.console.source import Accepted, SourceRefusal
from swarmtag.errors import RadioError
from swarmtag.tag import Change, MemoryStore, TagState
from swarmtag.tag.backends import Scanner, Sighting

__all__ = ["NO_KEY", "READY_S", "ScanDesk", "ScanSource", "bench_radio"]

READY_S: Final = 2.0
"""Seconds ``start`` waits for the radio to come up or fail (no adapter, no BlueZ)."""
NO_KEY: Final = (
    "this console holds no operator key, so it cannot sign writes: start it with "
    "--key-file OPERATOR.key (swarmtag tag keygen --role operator)"
)
_NO_FLOOR: Final = "real tags have no floor positions: the table lists the tags in range"
_STEP_S: Final = 0.02


class ScanSource:
    """The tags a scanner hears, as the console shows them."""

    kind = "scan"
    speed = 1.0

    def __init__(
        self,
        scanner: Scanner,
        *,
        ready_s: float = READY_S,
        on_written: Callable[[str, TagState], None] | None = None,
    ) -> None:
        self.scanner = scanner
        self.ready_s = ready_s
        self._on_written = on_written
        self._lock = threading.Lock()
        self._written: dict[int, tuple[float, TagState]] = {}
        self._writes = 0
        self._started: float | None = None

    def start(self) -> None:
        """Switch the radio on; raise its failure (``RadioError``) if it fails within ``ready_s``.

        A scanner that neither fails nor reports ``scanning`` by then is taken
        as working (the simulated and fake radios have no ``scanning`` flag).
        """
        self.scanner.start()
        self._started = self.scanner.now()
        deadline = time.monotonic() + self.ready_s
        while time.monotonic() < deadline:
            self.scanner.poll()
            if self.scanner.failure is not None:
                failure = self.scanner.failure
                self.scanner.stop()
                raise RadioError(f"--scan: {failure}")
            if getattr(self.scanner, "scanning", True):
                return
            time.sleep(_STEP_S)

    def stop(self) -> None:
        """Switch the radio off."""
        self.scanner.stop()

    def advance(self, seconds: float) -> int:
        """Let the radio catch up (the simulated one needs ``poll``); no steps of its own."""
        del seconds
        self.scanner.poll()
        return 0

    def _states(self) -> dict[int, tuple[Sighting, TagState]]:
        """Each tag in range: its sighting and its state (a newer accepted write's, if any)."""
        found = {}
        with self._lock:
            for marker, sighting in self.scanner.states().items():
                written = self._written.get(marker)
                if written is not None and written[0] >= sighting.seen_at:
                    found[marker] = (sighting, written[1])
                else:
                    self._written.pop(marker, None)
                    found[marker] = (sighting, sighting.state)
        return found

    @property
    def markers(self) -> frozenset[int]:
        """The tags in range now."""
        return frozenset(self.scanner.states())

    def address(self, marker: int) -> str:
        """The address the tag of ``marker`` was last heard from (``KeyError``: not in range)."""
        return self.scanner.states()[marker].address

    def tag_state(self, marker: int) -> TagState:
        """What the tag of ``marker`` holds, as heard or written (``KeyError``: not in range)."""
        return self._states()[marker][1]

    def apply(self, marker: int, address: str, after: TagState) -> None:
        """Show ``after`` (read back after an accepted write) until the tag is heard again."""
        with self._lock:
            self._written[marker] = (self.scanner.now(), after)
            self._writes += 1
        if self._on_written is not None:
            self._on_written(address, after)

    def snapshot(self) -> dict[str, Any]:
        """The tags in range: state, RSSI, address, seconds since heard; the radio's trouble."""
        now = self.scanner.now()
        tags = [
            {
                "marker": marker,
                "urgency": state.urgency,
                "status": state.status.name.lower(),
                "destination": state.destination,
                "last_heard": round(max(0.0, now - sighting.seen_at), 1),
                "carried_by": None,
                "rssi": sighting.rssi,
                "address": sighting.address,
                "x": None,
                "y": None,
                "present": False,
                "order_time": None,
                "delivered_at": None,
            }
            for marker, (sighting, state) in self._states().items()
        ]
        failure = self.scanner.failure
        return {
            "run": 0,
            "tick": None,
            "time": round(now - (self._started if self._started is not None else now), 1),
            "robots": [],
            "tags": tags,
            "radio": None if failure is None else str(failure),
        }

    def floor(self) -> dict[str, Any]:
        """No floor: real tags carry no position."""
        return {"kind": "none", "why": _NO_FLOOR, "destinations": list(range(256))}

    def kpis(self) -> dict[str, Any]:
        """What a scan measures: tags in range by status, urgencies, adverts, writes."""
        states = [state for _sighting, state in self._states().values()]
        statuses = [s.status.name.lower() for s in states]
        urgencies = [s.urgency for s in states]
        return {
            "kind": "scan",
            "tags": len(states),
            "awaiting_pickup": statuses.count("awaiting_pickup"),
            "picked_up": statuses.count("picked_up"),
            "idle": statuses.count("idle"),
            "mean_urgency": round(sum(urgencies) / len(urgencies), 2) if urgencies else None,
            "max_urgency": max(urgencies, default=None),
            "adverts": self.scanner.accepted,
            "foreign": self.scanner.foreign,
            "malformed": self.scanner.malformed,
            "writes": self._writes,
        }


class ScanDesk:
    """Writes to real tags with ``writer`` (a ``BleakTagWriter``; None: no operator key)."""

    def __init__(self, source: ScanSource, writer: Any | None) -> None:  # noqa: ANN401 - the ble extra's BleakTagWriter
        self.source = source
        self.writer = writer
        self._lock = threading.Lock()

    def write(self, marker: int, change: Change) -> Accepted:
        """Connect, read, sign, write, read back: the tag's answer (see ``BleakTagWriter``)."""
        if self.writer is None:
            raise SourceRefusal(NO_KEY)
        with self._lock:  # one connection at a time
            address = self.source.address(marker)
            outcome = self.writer.write(address, change, marker=marker)
            self.source.apply(marker, address, outcome.after)
            return Accepted(before=outcome.before, after=outcome.after, counter=outcome.counter)


def bench_radio(
    site_key: bytes,
) -> tuple[Scanner, Callable[..., Any], Callable[[str, TagState], None]]:
    """The simulated bench: its scanner, a loopback client factory, and the write-back hook.

    The bench tags (``swarmtag.tag.backends.sim.bench_tags``) become software
    tags holding ``site_key``; a write reaches them through the loopback GATT
    client, and an accepted one changes what the simulated radio hears.
    """
    from swarmtag.tag.backends.loopback import LoopbackClient  # noqa: PLC0415 - needs bleak
    from swarmtag.tag.backends.sim import SimScanner, SimTag, bench_tags  # noqa: PLC0415
    from swarmtag.tag.emulator import SoftwareTag  # noqa: PLC0415

    bench = [  # the bench's states at addresses a GATT writer takes
        SimTag(f"5E:7A:00:00:00:{t.state.marker:02X}", t.state, t.distance) for t in bench_tags()
    ]
    tags = {
        t.address: SoftwareTag.open(
            marker=t.state.marker,
            site_key=site_key,
            store=MemoryStore(),
            urgency=t.state.urgency,
            status=t.state.status,
            destination=t.state.destination,
        )
        for t in bench
    }
    scanner = SimScanner(tags=bench)

    def client(address: str, **options: Any) -> Any:  # noqa: ANN401 - bleak's options
        if address not in tags:
            raise RadioError(f"no tag answers at {address}")
        return LoopbackClient(address, tag=tags[address], **options)

    def heard(address: str, state: TagState) -> None:
        scanner.add(SimTag(address, state, next(t.distance for t in bench if t.address == address)))

    return scanner, client, heard
