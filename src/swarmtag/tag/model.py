"""The tag's logic: apply an authenticated write or refuse it, leaving nothing changed.

``TagModel`` is what runs on the nRF board (and in the software tag and the
simulator): it verifies the MAC, the target, the writer's counter and the
role's rights, persists the new record *before* acting on it (so a power
loss can never make a used counter usable again), and only then changes.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Protocol

from swarmtag.errors import ReplayedWrite, StateRecordError, WrongTarget
from swarmtag.tag.codec import TagState
from swarmtag.tag.lifecycle import apply_change
from swarmtag.tag.record import TagRecord
from swarmtag.tag.write import check_site_key, verify

__all__ = ["MemoryStore", "TagModel", "TagStore"]


class TagStore(Protocol):
    """Non-volatile memory for one tag's record (flash on the board, a file on a bench)."""

    def load(self) -> bytes | None:
        """The last saved record, or ``None`` if nothing was ever saved."""

    def save(self, record: bytes) -> None:
        """Persist ``record`` atomically: afterwards ``load`` returns it, even after a crash."""


class MemoryStore:
    """A store kept in memory: simulated flash that outlives a ``TagModel`` (a power cycle)."""

    def __init__(self) -> None:
        self._record: bytes | None = None

    def load(self) -> bytes | None:
        """The last saved record, or ``None``."""
        return self._record

    def save(self, record: bytes) -> None:
        """Keep ``record``."""
        self._record = bytes(record)


class TagModel:
    """One tag: its state, its writers' counters, and the rules for changing them.

    Create one with ``provision`` (factory setup) or ``boot`` (power-on from
    the persisted record).

    >>> from swarmtag.tag import Change, Role, TagStatus, WriteSigner
    >>> key = bytes(range(16))
    >>> store = MemoryStore()
    >>> tag = TagModel.provision(
    ...     TagState(urgency=5, status=TagStatus.AWAITING_PICKUP, destination=0, marker=12),
    ...     site_key=key, store=store)
    >>> robot = WriteSigner(writer=3, role=Role.ROBOT, key=key)
    >>> tag.apply(robot.sign(12, Change(status=TagStatus.PICKED_UP))).status.name
    'PICKED_UP'
    >>> TagModel.boot(site_key=key, store=store).counters  # after a power cycle
    mappingproxy({3: 0})
    """

    def __init__(self, record: TagRecord, *, site_key: bytes, store: TagStore) -> None:
        self._record = record
        self._key = check_site_key(site_key)
        self._store = store

    @classmethod
    def provision(cls, state: TagState, *, site_key: bytes, store: TagStore) -> TagModel:
        """Set up a tag from scratch: ``state``, no writers seen; persist it."""
        record = TagRecord(state=state)
        store.save(record.to_bytes())
        return cls(record, site_key=site_key, store=store)

    @classmethod
    def boot(cls, *, site_key: bytes, store: TagStore) -> TagModel:
        """Power on: restore state and counters from ``store``."""
        data = store.load()
        if data is None:
            raise StateRecordError("the tag's store is empty: provision the tag first")
        return cls(TagRecord.from_bytes(data), site_key=site_key, store=store)

    @property
    def state(self) -> TagState:
        """What the tag advertises now."""
        return self._record.state

    @property
    def counters(self) -> Mapping[int, int]:
        """Highest counter accepted from each writer id."""
        return self._record.counters

    def apply(self, message: bytes) -> TagState:
        """Apply one 20-byte write and return the new state, or raise ``WriteRejected``.

        A refused write changes nothing: not the state, not the counters, not the store.
        """
        write = verify(message, self._key)
        state = self._record.state
        if write.target != state.marker:
            raise WrongTarget(f"the write is for tag {write.target}, this is tag {state.marker}")
        last = self._record.counters.get(write.writer)
        if last is not None and write.counter <= last:
            raise ReplayedWrite(
                f"counter {write.counter} from writer {write.writer} is not above "
                f"the highest seen ({last}): replay refused"
            )
        new = TagRecord(
            state=apply_change(state, write.change, write.role),
            counters={**self._record.counters, write.writer: write.counter},
        )
        self._store.save(new.to_bytes())
        self._record = new
        return new.state
