"""The tag's logic: apply an authenticated write or refuse it, leaving nothing changed.

``TagModel`` is what runs on the nRF board (and in the software tag and the
simulator): it verifies the MAC (under the key of the role and writer id the
write names, derived from the site key it holds), the target, the writer's
counter, the role's rights, that a release comes from the robot that lifted
the carrier and that its writer table has room, persists the new record
*before* acting on it (so a power loss can never make a used counter usable
again), and only then changes.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import replace
from typing import Protocol, cast

from swarmtag.errors import (
    FieldRangeError,
    ReplayedWrite,
    StateRecordError,
    WriterTableFull,
    WrongTarget,
)
from swarmtag.tag._arguments import as_bytes, check_clock, check_type
from swarmtag.tag.claim import Claim, grant_claim, verify_claim
from swarmtag.tag.codec import TagState
from swarmtag.tag.lifecycle import apply_change, next_lifter
from swarmtag.tag.record import MAX_WRITERS, TagRecord
from swarmtag.tag.status import TagStatus
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
        """Keep ``record`` (bytes-like; anything else is a ``StateRecordError``)."""
        self._record = as_bytes("record", record, StateRecordError)


def _check_store(store: object) -> TagStore:
    """``store`` if it has callable ``load`` and ``save``; else ``FieldRangeError``."""
    if not all(callable(getattr(store, name, None)) for name in ("load", "save")):
        raise FieldRangeError(
            f"store: a {type(store).__name__} has no load() and save(); "
            "use MemoryStore, FileStore or another TagStore"
        )
    return cast("TagStore", store)


class TagModel:
    """One tag: its state, its writers' counters, and the rules for changing them.

    Create one with ``provision`` (factory setup) or ``boot`` (power-on from
    the persisted record).

    >>> from swarmtag.tag import Change, Role, TagStatus, WriteSigner, derive_robot_key
    >>> key = bytes(range(16))
    >>> store = MemoryStore()
    >>> tag = TagModel.provision(
    ...     TagState(urgency=5, status=TagStatus.AWAITING_PICKUP, destination=0, marker=12),
    ...     site_key=key, store=store)
    >>> robot = WriteSigner(writer=3, role=Role.ROBOT, key=derive_robot_key(key, 3))
    >>> tag.apply(robot.sign(12, Change(status=TagStatus.PICKED_UP))).status.name
    'PICKED_UP'
    >>> rebooted = TagModel.boot(site_key=key, store=store)  # after a power cycle
    >>> rebooted.counters, rebooted.lifter
    (mappingproxy({3: 0}), 3)
    """

    def __init__(self, record: TagRecord, *, site_key: bytes, store: TagStore) -> None:
        self._record = check_type("record", record, TagRecord)
        self._key = check_site_key(site_key)
        self._store = _check_store(store)
        self._claim: Claim | None = None

    @classmethod
    def provision(
        cls, state: TagState, *, site_key: bytes, store: TagStore, shared_robot_key: bool = False
    ) -> TagModel:
        """Set up a tag from scratch: ``state``, no writers seen, no lifter; persist it.

        ``shared_robot_key`` (legacy, off by default) makes the tag also accept
        robot writes under the one key all robots shared before per-robot keys.
        Every argument is checked before anything is saved.
        """
        record = TagRecord(state=state, shared_robot_key=shared_robot_key)
        tag = cls(record, site_key=site_key, store=store)
        tag._store.save(tag._record.to_bytes())
        return tag

    @classmethod
    def boot(cls, *, site_key: bytes, store: TagStore) -> TagModel:
        """Power on: restore state, settings, lifter and counters from ``store``.

        A version-1 record (written before per-robot keys) boots as a tag that
        accepts the shared robot key, as it did (``TagRecord``).
        """
        check_site_key(site_key)
        data = _check_store(store).load()
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

    @property
    def lifter(self) -> int | None:
        """The writer id of the robot that lifted the carrier (while PICKED_UP), or ``None``."""
        return self._record.lifter

    @property
    def shared_robot_key(self) -> bool:
        """Whether robot writes under the legacy shared robot key are accepted too."""
        return self._record.shared_robot_key

    def set_shared_robot_key(self, enabled: bool) -> None:
        """Turn acceptance of the legacy shared robot key on or off, and persist it.

        A provisioning setting (whoever holds the site key), not a write: the
        counters and the lifter are kept. Turn it off once every robot has its
        own key (docs/tag-protocol.md §4).
        """
        new = replace(self._record, shared_robot_key=enabled)  # checks ``enabled``
        if new != self._record:
            self._store.save(new.to_bytes())
            self._record = new

    def apply(self, message: bytes | bytearray | memoryview) -> TagState:
        """Apply one 20-byte write and return the new state, or raise ``WriteRejected``.

        A refused write changes nothing: not the state, not the counters, not the store.
        A message that is not bytes-like is a ``MalformedWrite``; a robot releasing a
        carrier another robot lifted is ``IllegalTransition``; a write from a new
        writer when ``MAX_WRITERS`` are already tracked is ``WriterTableFull``.
        """
        record = self._record
        # refuses a message that is not bytes-like, too
        write = verify(message, self._key, shared_robot_key=record.shared_robot_key)
        last = self._admit(write.writer, write.counter, write.target)
        new_state = apply_change(record.state, write.change, write.role)
        lifter = next_lifter(
            record.lifter,
            record.state.status,
            new_state.status,
            writer=write.writer,
            role=write.role,
        )
        self._room_for(write.writer, last)
        self._persist(new_state, write.writer, write.counter, lifter)
        if new_state.status is not TagStatus.AWAITING_PICKUP:
            self._claim = None  # a claim ends with the wait it reserved
        return new_state

    def claim(self, message: bytes | bytearray | memoryview, *, now: float) -> Claim:
        """Grant one claim write (``swarmtag.tag.claim``) at ``now`` (the tag's clock, s).

        Checked like ``apply`` (MAC first, target, counter, writer table),
        then ``grant_claim``; the counter is persisted, the claim kept in RAM.
        Raises a ``WriteRejected`` (``ClaimRefused`` among them) otherwise.
        """
        now = check_clock("now", now)
        write = verify_claim(message, self._key, shared_robot_key=self._record.shared_robot_key)
        last = self._admit(write.writer, write.counter, write.target)
        granted = grant_claim(write, status=self._record.state.status, held=self._claim, now=now)
        self._room_for(write.writer, last)
        self._persist(self._record.state, write.writer, write.counter, self._record.lifter)
        self._claim = granted
        return granted

    def claim_at(self, now: float) -> Claim | None:
        """The live claim at ``now``, or None (none granted, or ended)."""
        now = check_clock("now", now)
        if self._claim is not None and self._claim.seconds_left(now) == 0:
            self._claim = None
        return self._claim

    def _admit(self, writer: int, counter: int, target: int) -> int | None:
        """The writer's last counter, after refusing another tag's write or a replay."""
        state = self._record.state
        if target != state.marker:
            raise WrongTarget(f"the write is for tag {target}, this is tag {state.marker}")
        last = self._record.counters.get(writer)
        if last is not None and counter <= last:
            raise ReplayedWrite(
                f"counter {counter} from writer {writer} is not above "
                f"the highest seen ({last}): replay refused"
            )
        return last

    def _room_for(self, writer: int, last: int | None) -> None:
        """Refuse a new writer when the writer table is full."""
        if last is None and len(self._record.counters) >= MAX_WRITERS:
            raise WriterTableFull(
                f"tag {self._record.state.marker} already tracks {MAX_WRITERS} writers, the most "
                f"it can; writer {writer} is new and refused (reuse a known writer id, or rotate "
                "the site key and re-provision the tag)"
            )

    def _persist(self, state: TagState, writer: int, counter: int, lifter: int | None) -> None:
        """Save the new record first, then take it (a power loss keeps old or new)."""
        new = TagRecord(
            state=state,
            counters={**self._record.counters, writer: counter},
            lifter=lifter,
            shared_robot_key=self._record.shared_robot_key,
        )
        self._store.save(new.to_bytes())
        self._record = new
