"""What a tag keeps across power cycles: its state and each writer's highest counter.

Serialised as a small checksummed record (little-endian)::

    byte 0        record version (0x01)
    bytes 1-4     urgency, status, destination, marker
    bytes 5-6     number of writers n (uint16)
    n x 6 bytes   writer id (uint16), highest counter (uint32), sorted by writer id
    last 4 bytes  CRC-32 of everything before

The writer table holds at most ``MAX_WRITERS`` entries: with 512 the largest
record is 3,083 bytes, one 4 KiB flash page of the nRF52833 (SPEC §2.5), so
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

__all__ = ["MAX_WRITERS", "RECORD_VERSION", "TagRecord"]

RECORD_VERSION: Final = 0x01
MAX_WRITERS: Final = 512
"""Most writer ids one tag tracks: the largest record (3,083 bytes) fits one 4 KiB flash page."""
_MAX_WRITER_ID: Final = 0xFFFF
_MAX_COUNTER: Final = 0xFFFF_FFFF
_HEADER: Final = struct.Struct("<B4sH")
_ENTRY: Final = struct.Struct("<HI")
_CRC: Final = struct.Struct("<I")


@dataclass(frozen=True, slots=True)
class TagRecord:
    """A tag's persistent memory: advertised state plus per-writer replay counters.

    ``counters`` maps writer ids (0-65535) to counters (0-2³²-1), at most
    ``MAX_WRITERS`` of them; anything else is a ``FieldRangeError``.
    """

    state: TagState
    counters: Mapping[int, int] = field(default_factory=dict)

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
        data = as_bytes("tag record", data, StateRecordError)
        if len(data) < _HEADER.size + _CRC.size:
            raise StateRecordError(f"tag record has {len(data)} bytes, too short to be a record")
        body, (crc,) = data[: -_CRC.size], _CRC.unpack(data[-_CRC.size :])
        if zlib.crc32(body) != crc:
            raise StateRecordError("tag record checksum does not match: the record is corrupt")
        version, fields, count = _HEADER.unpack(body[: _HEADER.size])
        if version != RECORD_VERSION:
            raise StateRecordError(f"tag record version {version} is not supported")
        if count > MAX_WRITERS:
            raise StateRecordError(
                f"tag record says {count} writers, more than a tag tracks ({MAX_WRITERS})"
            )
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
