"""What a tag keeps across power cycles: its state and each writer's highest counter.

Serialised as a small checksummed record (little-endian)::

    byte 0        record version (0x01)
    bytes 1-4     urgency, status, destination, marker
    bytes 5-6     number of writers n (uint16)
    n x 6 bytes   writer id (uint16), highest counter (uint32), sorted by writer id
    last 4 bytes  CRC-32 of everything before
"""

from __future__ import annotations

import struct
import zlib
from collections.abc import Mapping
from dataclasses import dataclass, field
from types import MappingProxyType
from typing import Final

from swarmtag.errors import PayloadError, StateRecordError
from swarmtag.tag.codec import (
    COMPANY_ID,
    TagState,
    decode_manufacturer_data,
    encode_manufacturer_data,
)

__all__ = ["RECORD_VERSION", "TagRecord"]

RECORD_VERSION: Final = 0x01
_HEADER: Final = struct.Struct("<B4sH")
_ENTRY: Final = struct.Struct("<HI")
_CRC: Final = struct.Struct("<I")


@dataclass(frozen=True, slots=True)
class TagRecord:
    """A tag's persistent memory: advertised state plus per-writer replay counters."""

    state: TagState
    counters: Mapping[int, int] = field(default_factory=dict)

    def __post_init__(self) -> None:
        object.__setattr__(self, "counters", MappingProxyType(dict(sorted(self.counters.items()))))

    def to_bytes(self) -> bytes:
        """Serialise with a trailing CRC-32 so a torn or corrupted record is detected."""
        fields = encode_manufacturer_data(self.state)[COMPANY_ID]
        body = _HEADER.pack(RECORD_VERSION, fields, len(self.counters)) + b"".join(
            _ENTRY.pack(writer, counter) for writer, counter in self.counters.items()
        )
        return body + _CRC.pack(zlib.crc32(body))

    @classmethod
    def from_bytes(cls, data: bytes) -> TagRecord:
        """Parse a record; raise ``StateRecordError`` if it is truncated, corrupt or unknown."""
        if len(data) < _HEADER.size + _CRC.size:
            raise StateRecordError(f"tag record has {len(data)} bytes, too short to be a record")
        body, (crc,) = data[: -_CRC.size], _CRC.unpack(data[-_CRC.size :])
        if zlib.crc32(body) != crc:
            raise StateRecordError("tag record checksum does not match: the record is corrupt")
        version, fields, count = _HEADER.unpack(body[: _HEADER.size])
        if version != RECORD_VERSION:
            raise StateRecordError(f"tag record version {version} is not supported")
        entries = body[_HEADER.size :]
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
        return cls(state=state, counters=counters)
