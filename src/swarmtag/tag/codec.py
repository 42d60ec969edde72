"""The 6-byte advertisement payload (SPEC §2.1), as a record and as bytes.

A tag advertises manufacturer-specific data ``ff ff UU SS DD MM``: company id
0xFFFF, urgency 0-9, status, destination and marker id. BLE stacks hand the
same data over as ``{0xFFFF: bytes([UU, SS, DD, MM])}``; both forms are read
and written here. Decoding never raises anything but a ``PayloadError`` (also
for input that is not bytes at all); building a ``TagState`` from bad values
or encoding something else raises ``FieldRangeError``.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Final

from swarmtag.errors import (
    FieldRangeError,
    ForeignCompanyError,
    PayloadError,
    PayloadLengthError,
    UnknownStatusError,
    UrgencyRangeError,
)
from swarmtag.tag._arguments import as_bytes, check_int, check_type, describe
from swarmtag.tag.status import TagStatus

__all__ = [
    "COMPANY_ID",
    "FIELD_LENGTH",
    "MAX_URGENCY",
    "PAYLOAD_LENGTH",
    "TagState",
    "decode",
    "decode_manufacturer_data",
    "encode",
    "encode_manufacturer_data",
]

COMPANY_ID: Final = 0xFFFF
"""Bluetooth SIG company identifier reserved for tests and internal use."""
PAYLOAD_LENGTH: Final = 6
"""Bytes of the whole manufacturer-specific payload, company id included."""
FIELD_LENGTH: Final = 4
"""Bytes after the company id: urgency, status, destination, marker."""
MAX_URGENCY: Final = 9

# The field table: name, offset within the 4 field bytes, largest value.
_FIELDS: Final = (("urgency", 0, MAX_URGENCY), ("destination", 2, 255), ("marker", 3, 255))


@dataclass(frozen=True, slots=True)
class TagState:
    """What a tag advertises: urgency, status, destination and marker id.

    >>> TagState(urgency=7, status=TagStatus.AWAITING_PICKUP, destination=3, marker=12)
    TagState(urgency=7, status=<TagStatus.AWAITING_PICKUP: 1>, destination=3, marker=12)
    """

    urgency: int
    status: TagStatus
    destination: int
    marker: int

    def __post_init__(self) -> None:
        for name, _offset, high in _FIELDS:
            check_int(name, getattr(self, name), high)
        status: object = self.status  # callers without a type checker may pass 1 or "idle"
        if not isinstance(status, TagStatus):
            if isinstance(status, bool) or not isinstance(status, str | int):
                raise FieldRangeError(
                    f"status: {describe(status)} is not a TagStatus, a status name or 0-2"
                )
            object.__setattr__(self, "status", TagStatus.parse(status))


def encode_manufacturer_data(state: TagState) -> dict[int, bytes]:
    """The mapping form BLE stacks use: ``{0xFFFF: bytes([urgency, status, dest, marker])}``."""
    check_type("state", state, TagState)
    return {COMPANY_ID: bytes((state.urgency, state.status, state.destination, state.marker))}


def encode(state: TagState) -> bytes:
    r"""The 6-byte payload, company id first (0xFFFF reads the same in either byte order).

    >>> encode(TagState(urgency=7, status=TagStatus.AWAITING_PICKUP, destination=3, marker=12))
    b'\xff\xff\x07\x01\x03\x0c'
    """
    return COMPANY_ID.to_bytes(2, "little") + encode_manufacturer_data(state)[COMPANY_ID]


def _decode_fields(fields: bytes) -> TagState:
    if len(fields) != FIELD_LENGTH:
        raise PayloadLengthError(
            f"manufacturer data for company 0xffff has {len(fields)} bytes, expected {FIELD_LENGTH}"
        )
    urgency, status, destination, marker = fields
    if urgency > MAX_URGENCY:
        raise UrgencyRangeError(f"urgency byte is {urgency}, expected 0-{MAX_URGENCY}")
    try:
        known = TagStatus(status)
    except ValueError:
        raise UnknownStatusError(
            f"status byte is 0x{status:02x}, expected 0x00 IDLE, 0x01 AWAITING_PICKUP "
            "or 0x02 PICKED_UP"
        ) from None
    return TagState(urgency=urgency, status=known, destination=destination, marker=marker)


def decode(payload: bytes | bytearray | memoryview) -> TagState:
    """Read a 6-byte payload; raise a ``PayloadError`` subclass for anything else.

    >>> decode(bytes.fromhex("ffff0701030c")).marker
    12
    """
    data = as_bytes("payload", payload, PayloadError)
    if len(data) != PAYLOAD_LENGTH:
        raise PayloadLengthError(f"payload has {len(data)} bytes, expected {PAYLOAD_LENGTH}")
    company = int.from_bytes(data[:2], "little")
    if company != COMPANY_ID:
        raise ForeignCompanyError(f"company id is 0x{company:04x}, not 0x{COMPANY_ID:04x}")
    return _decode_fields(data[2:])


def decode_manufacturer_data(data: Mapping[int, bytes | bytearray | memoryview]) -> TagState:
    r"""Read the mapping form; entries of other companies are ignored.

    Raises ``ForeignCompanyError`` when no 0xFFFF entry is present, and
    ``PayloadError`` when ``data`` is not a mapping or its entry is not bytes.

    >>> decode_manufacturer_data({0x004C: b"\x02\x15", 0xFFFF: b"\x09\x02\x00\x05"}).urgency
    9
    """
    given: object = data  # callers without a type checker may pass anything
    if not isinstance(given, Mapping):
        raise PayloadError(
            f"manufacturer data: expected a mapping company id -> bytes, got {type(given).__name__}"
        )
    if COMPANY_ID not in data:
        others = ", ".join(sorted(map(_company, data))) or "none"
        raise ForeignCompanyError(f"no manufacturer data for company 0xffff (found: {others})")
    return _decode_fields(as_bytes("manufacturer data for 0xffff", data[COMPANY_ID], PayloadError))


def _company(key: object) -> str:
    """A company id as hex for a message; keys of the wrong type are shown, not sorted as ints."""
    if isinstance(key, int) and 0 <= key <= 0xFFFF:
        return f"0x{key:04x}"
    return describe(key)
