"""Authenticated tag writes (SPEC §2.3): the 20-byte format, signing and verifying.

Layout (multi-byte integers little-endian, as everywhere in BLE)::

    byte  0      format version (0x01)
    byte  1      flags: bits 0-1 role (1 robot, 2 operator),
                 bit 4 urgency present, bit 5 status present, bit 6 destination present;
                 bits 2, 3 and 7 are zero
    bytes 2-3    writer id (uint16)
    bytes 4-7    counter (uint32), strictly increasing per writer
    byte  8      target marker id: the tag this write is for
    byte  9      new urgency (0 when absent)
    byte  10     new status (0 when absent)
    byte  11     new destination (0 when absent)
    bytes 12-19  MAC: HMAC-SHA256(writer key, bytes 0-11) truncated to 8 bytes

The writer key (``swarmtag.tag.keys``) is, for a robot write, the key bound to
the writer id in bytes 2-3, ``derive_robot_key(site_key, writer)``, and for an
operator write the operator key, ``derive_role_key(site_key, Role.OPERATOR)``.
Writers hold only their own key; tags hold the site key and derive the key of
each write from its role bits and writer id, so a robot's key signs nothing
under another writer id. A tag set to accept the legacy shared robot key
(``shared_robot_key``) also takes a robot write under
``derive_role_key(site_key, Role.ROBOT)``. The MAC is checked before any other
field is interpreted, so a forger learns nothing from which error comes back;
role bits that name no role (0 or 3) select no key, so such a write never
verifies. Arguments of the wrong type or range raise ``FieldRangeError``
(``MalformedWrite`` for a message that is not bytes).
"""

from __future__ import annotations

import hashlib
import hmac
from dataclasses import dataclass
from typing import Final

from swarmtag.errors import FieldRangeError, ForgedWrite, MalformedWrite
from swarmtag.tag._arguments import as_bytes, check_int, check_type
from swarmtag.tag.codec import MAX_URGENCY
from swarmtag.tag.keys import (
    MIN_KEY_LENGTH,
    check_role_key,
    check_site_key,
    derive_robot_key,
    derive_role_key,
)
from swarmtag.tag.lifecycle import Change, Role, check_role
from swarmtag.tag.status import TagStatus

__all__ = [
    "MAC_LENGTH",
    "MIN_KEY_LENGTH",
    "WRITE_LENGTH",
    "WRITE_VERSION",
    "Write",
    "WriteSigner",
    "authenticated",
    "check_site_key",
    "mac",
    "sign",
    "verify",
    "writer_keys",
]

WRITE_LENGTH: Final = 20
"""One ATT write at the default MTU (23) carries 20 bytes of value."""
WRITE_VERSION: Final = 0x01
MAC_LENGTH: Final = 8
MAX_COUNTER: Final = 0xFFFF_FFFF

_SIGNED: Final = WRITE_LENGTH - MAC_LENGTH
_ROLE_BITS: Final = 0x03
_URGENCY_BIT: Final = 0x10
_STATUS_BIT: Final = 0x20
_DESTINATION_BIT: Final = 0x40
_KNOWN_BITS: Final = _ROLE_BITS | _URGENCY_BIT | _STATUS_BIT | _DESTINATION_BIT
_ROLES: Final = frozenset(int(role) for role in Role)


@dataclass(frozen=True, slots=True)
class Write:
    """One write's content before signing: who, which counter, which tag, what changes."""

    writer: int
    role: Role
    counter: int
    target: int
    change: Change

    def __post_init__(self) -> None:
        check_int("writer", self.writer, 0xFFFF)
        check_int("counter", self.counter, MAX_COUNTER)
        check_int("target", self.target, 0xFF)
        object.__setattr__(self, "role", check_role(self.role))
        if check_type("change", self.change, Change).empty:
            raise FieldRangeError("change: a write must set at least one field")
        if self.change.urgency is not None:
            check_int("urgency", self.change.urgency, MAX_URGENCY)
        if self.change.destination is not None:
            check_int("destination", self.change.destination, 0xFF)
        if self.change.status is not None and not isinstance(self.change.status, TagStatus):
            raise FieldRangeError(f"status: {self.change.status!r} is not a TagStatus")


def _mac(key: bytes, signed: bytes) -> bytes:
    return hmac.new(key, signed, hashlib.sha256).digest()[:MAC_LENGTH]


def sign(write: Write, key: bytes) -> bytes:
    """The 20 bytes to send for ``write``, signed with ``key``, the writer's key.

    ``key`` is ``derive_robot_key(site_key, write.writer)`` for a robot and
    ``derive_role_key(site_key, Role.OPERATOR)`` for an operator; under any
    other key (the site key itself, another robot's key) the tag refuses the
    write as forged.

    >>> key = derive_robot_key(b"k" * 16, 7)
    >>> msg = sign(Write(writer=7, role=Role.ROBOT, counter=1, target=12,
    ...                  change=Change(status=TagStatus.PICKED_UP)), key)
    >>> len(msg), msg[:12].hex()
    (20, '01210700010000000c000200')
    """
    change = check_type("write", write, Write).change
    flags = int(write.role)
    flags |= _URGENCY_BIT if change.urgency is not None else 0
    flags |= _STATUS_BIT if change.status is not None else 0
    flags |= _DESTINATION_BIT if change.destination is not None else 0
    signed = (
        bytes((WRITE_VERSION, flags))
        + write.writer.to_bytes(2, "little")
        + write.counter.to_bytes(4, "little")
        + bytes(
            (
                write.target,
                change.urgency or 0,
                int(change.status or 0),
                change.destination or 0,
            )
        )
    )
    return signed + _mac(check_role_key(key), signed)


def writer_keys(site_key: bytes, role: Role, writer: int, *, shared_robot_key: bool) -> list[bytes]:
    """The keys a tag accepts a write of ``role`` from ``writer`` under (one, or two if legacy).

    A robot: its own key, and the shared robot key too when the tag is set to
    accept it. An operator: the operator key.
    """
    if role is Role.OPERATOR:
        return [derive_role_key(site_key, Role.OPERATOR)]
    own = derive_robot_key(site_key, writer)
    return [own, derive_role_key(site_key, Role.ROBOT)] if shared_robot_key else [own]


def authenticated(
    message: bytes | bytearray | memoryview, key: bytes, *, shared_robot_key: bool = False
) -> tuple[bytes, Role]:
    """The signed 12 bytes of a 20-byte write whose MAC verifies, and the role it names.

    Every write format shares this: the length, then the MAC under the key
    of the role in byte 1's bits 0-1 and the writer id in bytes 2-3 (derived
    from the site key ``key``; ``writer_keys``), before anything else is read;
    ``MalformedWrite`` or ``ForgedWrite``. Every candidate key is tried, so
    the time taken does not say which one matched.
    """
    data = as_bytes("message", message, MalformedWrite)
    if len(data) != WRITE_LENGTH:
        raise MalformedWrite(f"a write is {WRITE_LENGTH} bytes, got {len(data)}")
    signed, tag = data[:_SIGNED], data[_SIGNED:]
    site_key = check_site_key(key)
    shared: object = shared_robot_key  # callers without a type checker may pass anything
    if not isinstance(shared, bool):
        raise FieldRangeError(
            f"shared_robot_key: expected True or False, got a {type(shared).__name__}"
        )
    role_bits = signed[1] & _ROLE_BITS
    verified = False
    if role_bits in _ROLES:
        writer = int.from_bytes(signed[2:4], "little")
        keys = writer_keys(site_key, Role(role_bits), writer, shared_robot_key=shared_robot_key)
        for candidate in keys:
            verified |= hmac.compare_digest(_mac(candidate, signed), tag)
    if not verified:
        raise ForgedWrite(
            "the write's MAC does not verify under the key of the role and writer id it names"
        )
    return signed, Role(role_bits)


def mac(key: bytes, signed: bytes) -> bytes:
    """The 8-byte MAC of the signed part of a write under a writer's key (HMAC-SHA256, cut)."""
    return _mac(check_role_key(key), signed)


def verify(
    message: bytes | bytearray | memoryview, key: bytes, *, shared_robot_key: bool = False
) -> Write:
    """Check the MAC under the named writer's key, then parse; raise a ``WriteRejected`` if bad.

    ``key`` is the site key (what a tag holds); ``shared_robot_key`` whether
    the tag also takes robot writes under the legacy shared robot key. Only
    the role bits of byte 1 and the writer id are read before the MAC has
    verified, to pick the key; a write whose MAC fails, or whose role bits
    name no role, is ``ForgedWrite``. After that, ``MalformedWrite`` for a
    bad version, reserved bits or field.
    """
    signed, role = authenticated(message, key, shared_robot_key=shared_robot_key)
    version, flags = signed[0], signed[1]
    if version != WRITE_VERSION:
        raise MalformedWrite(f"write format version {version} is not supported (expected 1)")
    if flags & ~_KNOWN_BITS:
        raise MalformedWrite(f"flags byte 0x{flags:02x} sets reserved bits")
    urgency, status, destination = signed[9], signed[10], signed[11]
    for bit, name, value in (
        (_URGENCY_BIT, "urgency", urgency),
        (_STATUS_BIT, "status", status),
        (_DESTINATION_BIT, "destination", destination),
    ):
        if not flags & bit and value:
            raise MalformedWrite(f"{name} byte is {value} but the flags say it is absent")
    if flags & _URGENCY_BIT and urgency > MAX_URGENCY:
        raise MalformedWrite(f"urgency {urgency} is not in 0-{MAX_URGENCY}")
    new_status: TagStatus | None = None
    if flags & _STATUS_BIT:
        try:
            new_status = TagStatus(status)
        except ValueError:
            raise MalformedWrite(f"status byte 0x{status:02x} is not a tag status") from None
    try:
        return Write(
            writer=int.from_bytes(signed[2:4], "little"),
            role=role,
            counter=int.from_bytes(signed[4:8], "little"),
            target=signed[8],
            change=Change(
                urgency=urgency if flags & _URGENCY_BIT else None,
                status=new_status,
                destination=destination if flags & _DESTINATION_BIT else None,
            ),
        )
    except FieldRangeError as error:  # an authentic write that sets no field
        raise MalformedWrite(str(error)) from None


@dataclass
class WriteSigner:
    """A writer's side: signs changes with its id, role, key and an increasing counter.

    ``key`` is the writer's own key: ``derive_robot_key(site_key, writer)``
    for a robot, ``derive_role_key(site_key, Role.OPERATOR)`` for an operator.
    A writer never needs the site key; a robot's key signs neither an
    operator's write nor another robot's. ``counter`` is the last counter
    used (-1: none yet); persist it across restarts (the tags refuse any
    counter they have already seen from this writer). Every argument is
    checked here, so a bad one fails at set-up, not at the first write.
    """

    writer: int
    role: Role
    key: bytes
    counter: int = -1

    def __post_init__(self) -> None:
        check_int("writer", self.writer, 0xFFFF)
        self.role = check_role(self.role)
        self.key = check_role_key(self.key)
        check_int("counter", self.counter, MAX_COUNTER, low=-1)

    def sign(self, target: int, change: Change) -> bytes:
        """Sign ``change`` for the tag with marker ``target`` using the next counter.

        A refused argument leaves ``counter`` as it was.
        """
        if check_int("counter", self.counter, MAX_COUNTER, low=-1) == MAX_COUNTER:
            raise FieldRangeError(
                f"counter: writer {self.writer} has used its last counter ({MAX_COUNTER}); "
                "retire this writer id and sign with a new one"
            )
        write = Write(
            writer=self.writer,
            role=self.role,
            counter=self.counter + 1,
            target=target,
            change=change,
        )
        message = sign(write, self.key)
        self.counter = write.counter
        return message
