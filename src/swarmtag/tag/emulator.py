"""The software tag: what a tag's GATT server does with each write, with no radio in it.

``SoftwareTag`` is the tag as its transport sees it. It wraps a ``TagModel``
and its ``TagStore`` and turns the raw value a central wrote to the
``WRITE`` characteristic into a ``WriteOutcome``: accepted, with the new
state; or refused, with the ATT error code to answer (``swarmtag.tag.gatt``)
and the state unchanged. It also gives what a transport shows of the
state: the advertisement's manufacturer data (company id 0xFFFF -> the 4
field bytes), the ``STATE`` characteristic's read and notify value (the same
4 bytes) and the E-ink picture. It counts accepted writes and refusals by
reason.

The BLE adapters (``swarmtag.tag.backends.bless``, the replay server) call
this from one thread; it does no I/O of its own beyond the store.

>>> from swarmtag.tag import Change, MemoryStore, Role, WriteSigner, derive_robot_key
>>> key = bytes(range(16))
>>> tag = SoftwareTag.open(marker=12, site_key=key, store=MemoryStore(), status="awaiting_pickup")
>>> robot = WriteSigner(writer=3, role=Role.ROBOT, key=derive_robot_key(key, 3))
>>> lift = robot.sign(12, Change(status=TagStatus.PICKED_UP))
>>> tag.write(lift).accepted, tag.state_value().hex()
(True, '0002000c')
>>> tag.write(lift).att_error  # the same bytes again: a replay
129
"""

from __future__ import annotations

from collections import Counter
from dataclasses import dataclass
from typing import TYPE_CHECKING, Final

from swarmtag.errors import FieldRangeError, WriteRejected
from swarmtag.tag._arguments import check_int, check_type
from swarmtag.tag.codec import COMPANY_ID, TagState, encode, encode_manufacturer_data
from swarmtag.tag.model import TagModel, TagStore
from swarmtag.tag.status import TagStatus
from swarmtag.tag.write import Write, check_site_key, verify

if TYPE_CHECKING:
    from PIL import Image

__all__ = ["ACCEPTED", "SoftwareTag", "WriteOutcome", "describe_outcome"]

ACCEPTED: Final = "accepted"
"""The key of accepted writes in ``SoftwareTag.counts`` (refusals count under their class name)."""


@dataclass(frozen=True, slots=True)
class WriteOutcome:
    """What the tag did with one value written to its ``WRITE`` characteristic.

    ``state`` is the tag's state after the write (unchanged when refused).
    ``write`` is the write's content when its MAC verified (``None`` for a
    malformed or forged value, whose fields mean nothing). A refusal has its
    ``att_error`` (the code the tag answers), the ``refusal`` class name
    (``ReplayedWrite``) and the ``reason``; an accepted write has
    ``att_error`` ``None``.
    """

    state: TagState
    write: Write | None
    att_error: int | None = None
    refusal: str = ""
    reason: str = ""

    @property
    def accepted(self) -> bool:
        """Whether the tag took the write (and changed, persisted and re-advertised)."""
        return self.att_error is None


class SoftwareTag:
    """One tag's logic behind a GATT server: writes in, outcomes and advertisement out.

    Build it with ``open`` (provision a new tag or boot a stored one),
    ``provision`` or ``boot``; each persists through ``store`` as
    ``TagModel`` does (the record is saved before a write takes effect).
    """

    def __init__(self, model: TagModel, *, site_key: bytes, provisioned: bool = False) -> None:
        self._model = check_type("model", model, TagModel)
        self._key = check_site_key(site_key)
        self._counts: Counter[str] = Counter()
        self.provisioned = bool(provisioned)
        """Whether this tag was set up from scratch when it was built (else it booted)."""

    @classmethod
    def provision(
        cls, state: TagState, *, site_key: bytes, store: TagStore, shared_robot_key: bool = False
    ) -> SoftwareTag:
        """A new tag in ``state`` with no writers seen, saved to ``store`` (overwriting it).

        ``shared_robot_key``: also accept the legacy shared robot key (``TagModel``).
        """
        model = TagModel.provision(
            state, site_key=site_key, store=store, shared_robot_key=shared_robot_key
        )
        return cls(model, site_key=site_key, provisioned=True)

    @classmethod
    def boot(cls, *, site_key: bytes, store: TagStore) -> SoftwareTag:
        """The tag saved in ``store``: its state and every writer's counter."""
        return cls(TagModel.boot(site_key=site_key, store=store), site_key=site_key)

    @classmethod
    def open(
        cls,
        *,
        marker: int,
        site_key: bytes,
        store: TagStore,
        urgency: int | None = None,
        status: TagStatus | str | int | None = None,
        destination: int | None = None,
        shared_robot_key: bool | None = None,
    ) -> SoftwareTag:
        """Boot the tag in ``store``, or provision it there if the store is empty.

        A new tag starts with ``urgency``, ``status`` and ``destination`` (by
        default 0, IDLE and 0: a tag fresh from provisioning carries nothing).
        A stored tag keeps what it has: giving any of those three for it is
        refused, and so is a ``marker`` other than the stored one
        (``FieldRangeError``), because re-provisioning under the same site key
        would reopen old counters to replay. ``shared_robot_key`` (legacy),
        if given, sets whether the tag also accepts the shared robot key, on a
        new tag (default off) or a stored one (saved at once; ``None`` keeps
        the stored setting).
        """
        check_int("marker", marker, 0xFF)
        given = {
            name: value
            for name, value in (
                ("urgency", urgency),
                ("status", status),
                ("destination", destination),
            )
            if value is not None
        }
        data = store.load() if callable(getattr(store, "load", None)) else None
        if data is None:
            state = TagState(
                urgency=0 if urgency is None else urgency,
                status=TagStatus.IDLE if status is None else TagStatus.parse(status),
                destination=0 if destination is None else destination,
                marker=marker,
            )
            shared = False if shared_robot_key is None else shared_robot_key
            return cls.provision(state, site_key=site_key, store=store, shared_robot_key=shared)
        tag = cls.boot(site_key=site_key, store=store)
        stored = tag.state.marker
        if stored != marker:
            raise FieldRangeError(
                f"marker: {marker} is not the stored tag's marker ({stored}); use marker "
                f"{stored}, or another state file for tag {marker}"
            )
        if given:
            names = ", ".join(given)
            raise FieldRangeError(
                f"{names}: only set up a new tag, and tag {stored} is already provisioned "
                f"({_fields(tag.state)}); change it with an operator write"
            )
        if shared_robot_key is not None:
            tag.set_shared_robot_key(shared_robot_key)
        return tag

    @property
    def state(self) -> TagState:
        """What the tag advertises now."""
        return self._model.state

    @property
    def shared_robot_key(self) -> bool:
        """Whether the tag also accepts robot writes under the legacy shared robot key."""
        return self._model.shared_robot_key

    def set_shared_robot_key(self, enabled: bool) -> None:
        """Turn acceptance of the legacy shared robot key on or off (saved; ``TagModel``)."""
        self._model.set_shared_robot_key(enabled)

    @property
    def counts(self) -> Counter[str]:
        """Writes so far: ``accepted`` and each refusal class name (a copy)."""
        return Counter(self._counts)

    @property
    def accepted(self) -> int:
        """Writes accepted so far."""
        return self._counts[ACCEPTED]

    @property
    def refused(self) -> int:
        """Writes refused so far, for any reason."""
        return sum(self._counts.values()) - self._counts[ACCEPTED]

    def write(self, value: bytes | bytearray | memoryview) -> WriteOutcome:
        """Apply one value written to ``WRITE``: accepted, or refused with its ATT code.

        Never raises a ``WriteRejected``: a refusal is an outcome, and leaves
        the state, the counters and the store as they were. A store that
        cannot save raises (``OSError``, ``StateRecordError``): the tag must
        not act on a write it could not persist.
        """
        try:
            shared = self._model.shared_robot_key
            write: Write | None = verify(value, self._key, shared_robot_key=shared)
        except WriteRejected:
            write = None  # the model refuses it again below, with the same error
        try:
            state = self._model.apply(value)
        except WriteRejected as refusal:
            self._counts[type(refusal).__name__] += 1
            return WriteOutcome(
                self.state,
                write,
                att_error=refusal.att_error,
                refusal=type(refusal).__name__,
                reason=refusal.reason,
            )
        self._counts[ACCEPTED] += 1
        return WriteOutcome(state, write)

    def manufacturer_data(self) -> dict[int, bytes]:
        """The advertisement's manufacturer data, as BLE stacks take it: ``{0xFFFF: 4 bytes}``."""
        return encode_manufacturer_data(self.state)

    def payload(self) -> bytes:
        """The whole 6-byte manufacturer-specific payload, company id first."""
        return encode(self.state)

    def state_value(self) -> bytes:
        """The ``STATE`` characteristic's value (read and notify): the 4 field bytes."""
        return self.manufacturer_data()[COMPANY_ID]

    def eink(self) -> Image.Image:
        """The 250 x 122 1-bit picture the tag's E-ink panel shows now (the ``eink`` extra)."""
        from swarmtag.tag.eink import render  # noqa: PLC0415 - Pillow, the eink extra

        return render(self.state)


def _fields(state: TagState) -> str:
    """A tag state in words, for messages: ``urgency 7, AWAITING_PICKUP, destination 3``."""
    return f"urgency {state.urgency}, {state.status.name}, destination {state.destination}"


def describe_outcome(outcome: WriteOutcome) -> str:
    """One line for a log: who wrote, and what the tag did (used by ``swarmtag tag emulate``)."""
    write = check_type("outcome", outcome, WriteOutcome).write
    who = (
        f"writer {write.writer} ({write.role.name.lower()}, counter {write.counter})"
        if write is not None
        else "an unverified writer"
    )
    if outcome.accepted:
        return f"accepted from {who}: now {_fields(outcome.state)}"
    code = f"ATT 0x{outcome.att_error:02x}"
    return f"refused from {who}: {outcome.refusal} ({code}): {outcome.reason}"
