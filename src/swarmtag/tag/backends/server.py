"""What every tag-side transport shares: the ``TagServer`` interface, and the replay server.

A scanner (``base.py``) is the robot's side of the radio; a tag server is the
tag's side: it serves one ``SoftwareTag`` (``swarmtag.tag.emulator``) to
centrals. A backend only has to hand every value written to the ``WRITE``
characteristic to ``_serve_write``, which applies it, keeps its
``WriteOutcome`` for ``outcomes()`` (what ``swarmtag tag emulate`` prints) and
stops the server if the tag's store could not save the write.

``ReplayTagServer`` takes its writes from a list instead of a radio: the
CLI's hidden ``--replay FILE`` (a bench test, or a test of the command
without a radio) and unit tests. The ``bless`` backend serves over BLE.
"""

from __future__ import annotations

import threading
from abc import abstractmethod
from collections import deque
from collections.abc import Iterable
from typing import ClassVar

from swarmtag.errors import FieldRangeError, StateRecordError, SwarmtagError
from swarmtag.tag._arguments import as_bytes, check_type
from swarmtag.tag.backends.base import Running
from swarmtag.tag.emulator import SoftwareTag, WriteOutcome

__all__ = ["ReplayTagServer", "TagServer"]


class TagServer(Running):
    """A running transport for one software tag; use as ``with server:``.

    ``outcomes()`` hands over the writes served since the last call, in
    order; ``failure`` says why the server stopped on its own (a radio that
    cannot be used, a store that cannot save), ``finished`` whether it has
    nothing more to serve (a replay that has run out; never for a radio).
    """

    name: ClassVar[str] = "server"

    def __init__(self, tag: SoftwareTag) -> None:
        self.tag = check_type("tag", tag, SoftwareTag)
        self._outcomes: deque[WriteOutcome] = deque()
        self._lock = threading.Lock()
        self._failure: SwarmtagError | None = None

    @abstractmethod
    def start(self) -> None:
        """Begin serving (advertise, accept connections); the failure, if any, is ``failure``."""

    @abstractmethod
    def stop(self) -> None:
        """Stop serving and release the radio; the tag keeps its state and store."""

    def poll(self) -> None:
        """Serve what is due now, for backends without a thread of their own."""

    @property
    def failure(self) -> SwarmtagError | None:
        """Why the server stopped on its own, or ``None`` while it serves."""
        return self._failure

    @property
    def finished(self) -> bool:
        """Whether there is nothing more to serve (a radio serves until ``stop``)."""
        return False

    def outcomes(self) -> list[WriteOutcome]:
        """The outcomes of the writes served since the last call, oldest first."""
        with self._lock:
            taken = list(self._outcomes)
            self._outcomes.clear()
        return taken

    def _serve_write(self, value: bytes) -> WriteOutcome | None:
        """Apply one written value and keep its outcome; ``None`` if the store failed.

        A store that cannot save (``OSError``, ``StateRecordError``) ends the
        server: ``failure`` says so, and the write is not acted on.
        """
        with self._lock:
            try:
                outcome = self.tag.write(value)
            except OSError as error:
                self._failure = StateRecordError(
                    f"the tag's state could not be saved, so it stopped serving: "
                    f"{error.strerror or error}"
                )
                return None
            except StateRecordError as error:
                self._failure = StateRecordError(
                    f"the tag's state could not be saved, so it stopped serving: {error}"
                )
                return None
            self._outcomes.append(outcome)
            return outcome


class ReplayTagServer(TagServer):
    """Serve writes from a list, in order, as if centrals had written them one by one.

    Each ``poll()`` after ``start()`` serves every write not yet served;
    ``finished`` is true once all were (or the store failed).

    >>> from swarmtag.tag import MemoryStore
    >>> tag = SoftwareTag.open(marker=12, site_key=bytes(16), store=MemoryStore())
    >>> with ReplayTagServer(tag, [bytes(20)]) as server:
    ...     server.poll()
    >>> [(o.refusal, o.att_error) for o in server.outcomes()], server.finished
    ([('ForgedWrite', 128)], True)
    """

    name = "replay"

    def __init__(self, tag: SoftwareTag, writes: Iterable[bytes | bytearray | memoryview]) -> None:
        super().__init__(tag)
        if isinstance(writes, bytes | bytearray | memoryview | str) or not isinstance(
            writes, Iterable
        ):
            raise FieldRangeError(
                f"writes: expected a list of written values, got {type(writes).__name__}"
            )
        self._pending = deque(as_bytes("write", value, FieldRangeError) for value in writes)
        self._running = False

    def start(self) -> None:
        """Begin serving the writes (on the next ``poll``)."""
        self._running = True

    def stop(self) -> None:
        """Serve nothing more; writes not yet served stay unserved."""
        self._running = False

    def poll(self) -> None:
        """Serve every pending write, unless stopped or the store failed."""
        while self._running and self._pending and self._failure is None:
            self._serve_write(self._pending.popleft())

    @property
    def finished(self) -> bool:
        """Whether every write was served, or the store failed."""
        return not self._pending or self._failure is not None
