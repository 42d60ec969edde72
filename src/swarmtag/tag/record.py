"""What a tag keeps across power cycles: its state, settings, lifter and writers' counters.

Serialised as a small checksummed record (little-endian), version 2::

    byte 0        record version (0x02)
    bytes 1-4     urgency, status, destination, marker
    byte 5        flags: bit 0 the tag accepts the legacy shared robot key,
                  bit 1 a lifter is remembered; other bits zero
    bytes 6-7     the lifter's writer id (uint16; 0 when bit 1 is clear)
    bytes 8-9     number of writers n (uint16)
    n x 6 bytes   writer id (uint16), highest counter (uint32), sorted by writer id
    last 4 bytes  CRC-32 of everything before

A version-1 record (what tags wrote before per-robot keys: no bytes 5-7)
still boots: as a tag that accepts the shared robot key, as it did, with no
lifter remembered. The next save writes version 2, keeping that setting.

The writer table holds at most ``MAX_WRITERS`` entries: with 512 the largest
record is 3,086 bytes, one 4 KiB flash page of the nRF52833 (SPEC §2.5), so
the old and the new record fit in two pages. The 16-bit count could say more,
but a record claiming more writers than a tag can track is refused.
"""

from __future__ import annotations

import struct
import zlib
from collections.abc import Mapping
from dataclasses import dataclass, field
from types import MappingProxyType
from typing import Final

from swarmtag.errors import FieldRangeError, PayloadError, StateRecordError
from swarmtag.tag._arguments import as_bytes, check_int, check_type
from swarmtag.tag.codec import (
    COMPANY_ID,
    TagState,
    decode_manufacturer_data,
    encode_manufacturer_data,
)
from swarmtag.tag.status import TagStatus

__all__ = ["LEGACY_RECORD_VERSION", "MAX_WRITERS", "RECORD_VERSION", "TagRecord"]

RECORD_VERSION: Final = 0x02
"""The record version written."""
LEGACY_RECORD_VERSION: Final = 0x01
"""The record version before per-robot keys: read, never written."""
MAX_WRITERS: Final = 512
"""Most writer ids one tag tracks: the largest record (3,086 bytes) fits one 4 KiB flash page."""
_MAX_WRITER_ID: Final = 0xFFFF
_MAX_COUNTER: Final = 0xFFFF_FFFF
_SHARED_ROBOT_KEY: Final = 0x01
_LIFTER: Final = 0x02
_HEADER: Final = struct.Struct("<B4sBHH")
_LEGACY_HEADER: Final = struct.Struct("<B4sH")
_ENTRY: Final = struct.Struct("<HI")
_CRC: Final = struct.Struct("<I")


@dataclass(frozen=True, slots=True)
class TagRecord:
    """A tag's persistent memory: advertised state, settings, lifter, per-writer counters.

    ``counters`` maps writer ids (0-65535) to counters (0-2³²-1), at most
    ``MAX_WRITERS`` of them. ``lifter`` is the writer id of the robot that
    lifted the carrier (only while PICKED_UP; ``None``: none known).
    ``shared_robot_key`` is whether the tag also accepts robot writes under
    the legacy shared robot key (off for new tags). Anything else is a
    ``FieldRangeError``.
    """

    state: TagState
    counters: Mapping[int, int] = field(default_factory=dict)
    lifter: int | None = None
    shared_robot_key: bool = False

    def __post_init__(self) -> None:
        check_type("state", self.state, TagState)
        counters: object = self.counters
        if not isinstance(counters, Mapping):
            raise FieldRangeError(
                f"counters: expected a mapping writer id -> counter, got {type(counters).__name__}"
            )
        if len(counters) > MAX_WRITERS:
            raise FieldRangeError(
                f"counters: {len(counters)} writers, a tag tracks at most {MAX_WRITERS}"
            )
        table = {
            check_int("writer id", writer, _MAX_WRITER_ID): check_int(
                "counter", counter, _MAX_COUNTER
            )
            for writer, counter in counters.items()
        }
        object.__setattr__(self, "counters", MappingProxyType(dict(sorted(table.items()))))
        shared: object = self.shared_robot_key  # callers without a type checker may pass anything
        if not isinstance(shared, bool):
            shown = type(shared).__name__
            raise FieldRangeError(f"shared_robot_key: expected True or False, got a {shown}")
        if self.lifter is not None:
            check_int("lifter", self.lifter, _MAX_WRITER_ID)
            if self.state.status is not TagStatus.PICKED_UP:
                raise FieldRangeError(
                    f"lifter: a tag remembers a lifter only while PICKED_UP, "
                    f"not {self.state.status.name}"
                )

    def to_bytes(self) -> bytes:
        """Serialise (version 2) with a trailing CRC-32 so a torn or corrupt record is detected."""
        fields = encode_manufacturer_data(self.state)[COMPANY_ID]
        flags = (_SHARED_ROBOT_KEY if self.shared_robot_key else 0) | (
            _LIFTER if self.lifter is not None else 0
        )
        lifter = self.lifter or 0
        body = _HEADER.pack(RECORD_VERSION, fields, flags, lifter, len(self.counters)) + b"".join(
            _ENTRY.pack(writer, counter) for writer, counter in self.counters.items()
        )
        return body + _CRC.pack(zlib.crc32(body))

    @classmethod
    def from_bytes(cls, data: bytes) -> TagRecord:
        """Parse a record (version 2 or 1); ``StateRecordError`` if short, corrupt or unknown."""
        data = as_bytes("tag record", data, StateRecordError)
        if len(data) < _LEGACY_HEADER.size + _CRC.size:
            raise StateRecordError(f"tag record has {len(data)} bytes, too short to be a record")
        body, (crc,) = data[: -_CRC.size], _CRC.unpack(data[-_CRC.size :])
        if zlib.crc32(body) != crc:
            raise StateRecordError("tag record checksum does not match: the record is corrupt")
        version = body[0]
        if version == LEGACY_RECORD_VERSION:
            _version, fields, count = _LEGACY_HEADER.unpack(body[: _LEGACY_HEADER.size])
            flags, lifter, entries = _SHARED_ROBOT_KEY, 0, body[_LEGACY_HEADER.size :]
        elif version == RECORD_VERSION and len(body) >= _HEADER.size:
            _version, fields, flags, lifter, count = _HEADER.unpack(body[: _HEADER.size])
            entries = body[_HEADER.size :]
        elif version == RECORD_VERSION:
            raise StateRecordError(f"tag record has {len(data)} bytes, too short to be a record")
        else:
            raise StateRecordError(f"tag record version {version} is not supported")
        if flags & ~(_SHARED_ROBOT_KEY | _LIFTER) or (lifter and not flags & _LIFTER):
            raise StateRecordError(f"tag record flags 0x{flags:02x} and lifter do not agree")
        if count > MAX_WRITERS:
            raise StateRecordError(
                f"tag record says {count} writers, more than a tag tracks ({MAX_WRITERS})"
            )
        if len(entries) != count * _ENTRY.size:
            raise StateRecordError(
                f"tag record says {count} writers but holds {len(entries)} bytes of entries"
            )
        try:
            state = decode_manufacturer_data({COMPANY_ID: fields})
        except PayloadError as error:
            raise StateRecordError(f"tag record holds an invalid state: {error}") from None
        counters = dict(_ENTRY.iter_unpack(entries))
        if len(counters) != count:
            raise StateRecordError("tag record lists a writer twice")
        try:
            return cls(
                state=state,
                counters=counters,
                lifter=lifter if flags & _LIFTER else None,
                shared_robot_key=bool(flags & _SHARED_ROBOT_KEY),
            )
        except FieldRangeError as error:  # a lifter on a tag that is not PICKED_UP
            raise StateRecordError(f"tag record is inconsistent: {error}") from None
