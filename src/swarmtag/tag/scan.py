"""Scanner-side filtering: keep our tags, ignore the rest of the room, count everything.

A robot's radio hears every BLE device nearby. ``ScanFilter.feed`` turns one
advertisement's manufacturer data into a ``TagState``, or ``None`` when it is
not ours (no 0xFFFF entry) or is malformed; nothing is ever raised, and the
counters say what was seen so a field engineer can spot a broken tag.
"""

from __future__ import annotations

from collections import Counter
from collections.abc import Mapping
from dataclasses import dataclass, field

from swarmtag.errors import ForeignCompanyError, PayloadError
from swarmtag.tag.codec import TagState, decode, decode_manufacturer_data

__all__ = ["ScanFilter"]


@dataclass
class ScanFilter:
    r"""Decode advertisements without ever raising; count accepted, foreign and malformed ones.

    >>> scan = ScanFilter()
    >>> scan.feed({0x004C: b"\x10\x05"}) is None  # a phone nearby: not ours
    True
    >>> scan.feed({0xFFFF: b"\x07\x01\x03\x0c"}).urgency
    7
    >>> scan.feed({0xFFFF: b"\x0a\x01\x03\x0c"}) is None  # urgency 10: malformed
    True
    >>> (scan.accepted, scan.foreign, scan.malformed)
    (1, 1, 1)
    """

    accepted: int = 0
    foreign: int = 0
    errors: Counter[str] = field(default_factory=Counter)
    """Malformed payloads by error class name (e.g. ``UrgencyRangeError``)."""

    @property
    def malformed(self) -> int:
        """How many payloads claimed to be ours but could not be decoded."""
        return sum(self.errors.values())

    def feed(self, manufacturer_data: Mapping[int, bytes] | bytes) -> TagState | None:
        """Decode the mapping form (or raw 6-byte form); ``None`` if foreign or malformed."""
        try:
            if isinstance(manufacturer_data, Mapping):
                state = decode_manufacturer_data(manufacturer_data)
            else:
                state = decode(manufacturer_data)
        except ForeignCompanyError:
            self.foreign += 1
            return None
        except PayloadError as error:
            self.errors[type(error).__name__] += 1
            return None
        self.accepted += 1
        return state
