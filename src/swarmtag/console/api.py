"""The console's API as plain functions of plain values: no HTTP here, so tests call it directly.

``ConsoleCore`` answers each API call with a ``Reply`` (an HTTP status and a
JSON-ready body): the tag list, the floor, the KPIs so far, a tag's E-ink
picture, and operator writes. A write is checked in this order, and the
first failure answers with nothing changed and one ``error`` line: body
size (413), JSON and field (400), value range (422), marker (404), the
client's write rate (429), what the source can carry out (409), and the
tag's own verdict on the signed write (409, the tag's reason). Every write
attempt past authentication, accepted or refused, goes to the audit log.
"""

from __future__ import annotations

import json
import threading
import time
from dataclasses import dataclass
from typing import Any, Final

from swarmtag.console.audit import AuditLog
from swarmtag.console.auth import RateLimiter
from swarmtag.console.source import ConsoleSource, Desk, SourceRefusal
from swarmtag.errors import FieldRangeError, SwarmtagError, WriteRejected
from swarmtag.tag import Change, TagStatus

__all__ = ["FIELDS", "MAX_BODY", "ConsoleCore", "Reply"]

MAX_BODY: Final = 1024
"""Bytes a write's body may have (``{"urgency": 9}`` is 14)."""
FIELDS: Final = ("urgency", "status", "destination")
"""The fields an operator may write, one per request."""
_KPI_CACHE_S: Final = 0.5


@dataclass(frozen=True)
class Reply:
    """An API answer: HTTP status and JSON body."""

    status: int
    body: Any


class _Refused(Exception):
    """A write refused before or by the tag: the HTTP status and the one-line reason."""

    def __init__(self, status: int, message: str) -> None:
        super().__init__(message)
        self.status = status
        self.message = message


def _error(status: int, message: str) -> Reply:
    return Reply(status, {"error": message})


def _value(field: str, raw: object) -> int | TagStatus:
    """The value of ``field`` from the body, or ``FieldRangeError`` naming what is allowed."""
    if field == "status":
        if not isinstance(raw, str | int) or isinstance(raw, bool):
            raise TypeError("status: give a name (idle, awaiting_pickup, picked_up) or 0-2")
        return TagStatus.parse(raw)
    if isinstance(raw, bool) or not isinstance(raw, int):
        raise TypeError(f"{field}: give an integer")
    high = 9 if field == "urgency" else 255
    if not 0 <= raw <= high:
        raise FieldRangeError(f"{field}: {raw} is not in 0-{high}")
    return raw


class ConsoleCore:
    """The API over a source, its operator desk, the audit log and the write rate."""

    def __init__(
        self,
        source: ConsoleSource,
        desk: Desk,
        audit: AuditLog,
        *,
        limiter: RateLimiter | None = None,
        overdue_s: float = 90.0,
    ) -> None:
        self.source = source
        self.desk = desk
        self.audit = audit
        self.limiter = limiter or RateLimiter()
        self.overdue_s = overdue_s
        self._kpis: tuple[float, dict[str, Any]] | None = None
        self._kpi_lock = threading.Lock()

    def state(self) -> dict[str, Any]:
        """The moving parts (time, robots, tags with their ``overdue`` flag)."""
        snap = self.source.snapshot()
        now = snap["time"]
        for tag in snap["tags"]:
            ordered = tag.get("order_time")
            if ordered is None:  # real tags: no order time, so nothing is overdue
                tag["waited"], tag["overdue"] = None, False
                continue
            waiting = tag["status"] != "idle" and tag.get("delivered_at") is None
            tag["waited"] = round(now - ordered, 3)
            tag["overdue"] = waiting and tag["waited"] > self.overdue_s
        return snap

    def tags(self) -> Reply:
        """``GET /api/tags``."""
        return Reply(200, self.state()["tags"])

    def kpis(self) -> Reply:
        """``GET /api/kpis`` (computed at most twice a second)."""
        with self._kpi_lock:
            now = time.monotonic()
            if self._kpis is None or now - self._kpis[0] > _KPI_CACHE_S:
                self._kpis = (now, self.source.kpis())
            return Reply(200, self._kpis[1])

    def floor(self) -> Reply:
        """``GET /api/floor``: the source's still picture, what it is, and the overdue limit."""
        return Reply(
            200,
            {
                **self.source.floor(),
                "source": self.source.kind,
                "overdue_s": self.overdue_s,
                "speed": self.source.speed,
            },
        )

    def control(self, body: bytes) -> Reply:
        """``POST /api/replay``: play, pause, seek or change the speed of a replay."""
        control = getattr(self.source, "control", None)
        if control is None:
            return _error(409, f"the {self.source.kind} source has no replay controls")
        if len(body) > MAX_BODY:
            return _error(413, f"the body is over {MAX_BODY} bytes")
        try:
            data = json.loads(body)
        except (ValueError, UnicodeDecodeError):
            return _error(400, 'the body is not JSON; send e.g. {"playing": false}')
        try:
            answer: dict[str, Any] = control(data)
        except SwarmtagError as error:
            return _error(422, str(error))
        return Reply(200, answer)

    def marker(self, text: str) -> int | Reply:
        """The marker id in a path, or a 404 reply."""
        if not text.isdecimal() or len(text) > 3 or int(text) not in self.source.markers:
            where = "in range" if self.source.kind == "scan" else "on this floor"
            return _error(404, f"no tag with marker {text[:20]!r} {where}")
        return int(text)

    def eink(self, text: str) -> Reply | bytes:
        """``GET /api/tags/{marker}/eink``: the tag's E-ink picture as PNG bytes."""
        from swarmtag.tag.eink import png_bytes  # noqa: PLC0415 - Pillow is an extra

        marker = self.marker(text)
        if isinstance(marker, Reply):
            return marker
        try:
            return png_bytes(self.source.tag_state(marker))
        except KeyError:
            return _error(404, f"tag {marker} is not there now")

    def write(self, *, who: str, client: str, marker: str, field: str, body: bytes) -> Reply:
        """``POST /api/tags/{marker}/{field}``; the reply and its audit line."""
        change: dict[str, object] = {"field": field[:20]}
        try:
            reply = self._write(client=client, marker=marker, field=field, body=body, change=change)
        except _Refused as refused:
            reply = _error(refused.status, refused.message)
        accepted = reply.status == 200
        self.audit.record(
            who=who,
            tag=marker[:20],
            change=change,
            outcome="accepted" if accepted else "refused",
            status=reply.status,
            reason=None if accepted else str(reply.body["error"]),
        )
        return reply

    def _parse(self, field: str, body: bytes, change: dict[str, object]) -> Change:
        """The change a body asks for; ``_Refused`` says what is wrong with it."""
        if field not in FIELDS:
            raise _Refused(
                404, f"no field {field[:20]!r}: write one of {', '.join(FIELDS)}"
            ) from None
        if len(body) > MAX_BODY:
            raise _Refused(413, f"the body is over {MAX_BODY} bytes")
        try:
            data = json.loads(body)
        except (ValueError, UnicodeDecodeError):
            raise _Refused(400, f'the body is not JSON; send {{"{field}": VALUE}}') from None
        if not isinstance(data, dict) or set(data) != {field}:
            raise _Refused(400, f'send exactly one key, {{"{field}": VALUE}}') from None
        raw = data[field]
        change["value"] = raw if isinstance(raw, int | str) else repr(raw)
        try:
            value = _value(field, raw)
        except TypeError as error:
            raise _Refused(400, str(error)) from None
        except FieldRangeError as error:
            raise _Refused(422, str(error)) from None
        if isinstance(value, TagStatus):
            return Change(status=value)
        return Change(urgency=value) if field == "urgency" else Change(destination=value)

    def _write(
        self,
        *,
        client: str,
        marker: str,
        field: str,
        body: bytes,
        change: dict[str, object],
    ) -> Reply:
        """Carry out a write; ``_Refused`` with the status and reason if it is not done."""
        asked = self._parse(field, body, change)
        found = self.marker(marker)
        if isinstance(found, Reply):
            return found
        if not self.limiter.allow(client):
            raise _Refused(429, "too many writes from this client; wait a moment")
        try:
            accepted = self.desk.write(found, asked)
        except KeyError:
            where = "in range" if self.source.kind == "scan" else "on the floor"
            raise _Refused(404, f"tag {found} is not {where} now") from None
        except (SourceRefusal, WriteRejected) as error:
            raise _Refused(409, f"refused: {error}") from None
        except SwarmtagError as error:  # e.g. the counter file cannot be written
            raise _Refused(503, f"not written: {error}") from None
        after = accepted.after
        change["counter"] = accepted.counter
        return Reply(
            200,
            {
                "marker": after.marker,
                "urgency": after.urgency,
                "status": after.status.name.lower(),
                "destination": after.destination,
                "counter": accepted.counter,
            },
        )
