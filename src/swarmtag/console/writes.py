"""The console's write path: sign an operator change, let the tag verify it, then apply it.

The server holds the operator key (never the browser). Each change is
signed as a 20-byte operator write (``swarmtag.tag.write``) with a counter
reserved first in the operator's counter file (``swarmtag.tag.counter``,
as ``swarmtag tag write`` does), and handed to the tag: a ``TagModel``
holding the source's site key, the carrier's current state and the
counters it has accepted so far. The tag verifies the MAC, the target and
the counter and applies the lifecycle rules; only a write it accepted is
carried out by the source. A write signed under any other key, or replayed,
is refused by the tag (``WriteRejected``) and changes nothing.
"""

from __future__ import annotations

import threading
from typing import Protocol

from swarmtag.console.source import Accepted, SourceRefusal
from swarmtag.tag import Change, MemoryStore, Role, TagModel, TagState
from swarmtag.tag.counter import CounterFile
from swarmtag.tag.record import TagRecord
from swarmtag.tag.write import Write, sign

__all__ = ["Accepted", "OperatorDesk", "ReadOnlyDesk", "WritableSource"]


class WritableSource(Protocol):
    """What the desk needs of a source: the tags' site key, their state, and the change."""

    site_key: bytes

    def tag_state(self, marker: int) -> TagState:
        """The tag's state now (``KeyError``: no such tag)."""
        ...

    def check_change(self, marker: int, change: Change) -> None:
        """Refuse a change the source cannot carry out, before anything is signed."""
        ...

    def apply(self, marker: int, before: TagState, after: TagState) -> None:
        """Carry out a change the tag accepted."""
        ...


class OperatorDesk:
    """Signs operator writes with ``key`` as writer ``writer`` and applies them to ``source``."""

    def __init__(
        self, source: WritableSource, *, key: bytes, writer: int, counters: CounterFile
    ) -> None:
        self.source = source
        self.writer = writer
        self._key = key
        self._counters = counters
        self._seen: dict[int, dict[int, int]] = {}
        self._lock = threading.Lock()
        counters.check()

    def write(self, marker: int, change: Change) -> Accepted:
        """Sign ``change`` for ``marker``'s tag, have the tag apply it, carry it out.

        Raises ``KeyError`` (no such tag), ``SourceRefusal`` (the source cannot
        carry it out; nothing signed) or a ``WriteRejected`` (the tag refused;
        that counter is spent, as on a real tag).
        """
        with self._lock:
            before = self.source.tag_state(marker)
            self.source.check_change(marker, change)
            counter = self._counters.reserve(self.writer)
            message = sign(
                Write(
                    writer=self.writer,
                    role=Role.OPERATOR,
                    counter=counter,
                    target=marker,
                    change=change,
                ),
                self._key,
            )
            after = self.deliver(marker, before, message)
            self.source.apply(marker, before, after)
            return Accepted(before=before, after=after, counter=counter)

    def deliver(self, marker: int, state: TagState, message: bytes) -> TagState:
        """The tag's answer to ``message``: its new state, or a ``WriteRejected``.

        The tag holds ``state`` and the counters it accepted before; a refused
        write leaves both as they were.
        """
        seen = self._seen.setdefault(marker, {})
        tag = TagModel(
            TagRecord(state=state, counters=dict(seen)),
            site_key=self.source.site_key,
            store=MemoryStore(),
        )
        after = tag.apply(message)
        seen.update(tag.counters)
        return after


class ReadOnlyDesk:
    """The desk of a source that takes no writes: every write is refused, nothing signed."""

    def __init__(self, reason: str) -> None:
        self.reason = reason

    def write(self, marker: int, change: Change) -> Accepted:
        """Refuse: ``SourceRefusal`` with the reason (HTTP 409, audited as every refusal)."""
        del marker, change
        raise SourceRefusal(self.reason)
