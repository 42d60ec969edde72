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
from typing import Final

from swarmtag.errors import FieldRangeError, ForeignCompanyError, PayloadError
from swarmtag.tag._arguments import check_int
from swarmtag.tag.codec import TagState, decode, decode_manufacturer_data

__all__ = ["ScanFilter"]

_MAX_COUNT: Final = 2**63 - 1
"""Largest starting count accepted: far beyond any scan, and a signed 64-bit value."""


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

    def __post_init__(self) -> None:
        """Refuse starting counts that ``feed`` could not add to (``FieldRangeError``)."""
        check_int("accepted", self.accepted, _MAX_COUNT)
        check_int("foreign", self.foreign, _MAX_COUNT)
        errors: object = self.errors
        if not isinstance(errors, Counter):
            raise FieldRangeError(f"errors: expected a Counter, got {type(errors).__name__}")
        for name, count in errors.items():
            if not isinstance(name, str):
                raise FieldRangeError(
                    f"errors: keys are error class names, got {type(name).__name__}"
                )
            check_int(f"errors[{name!r}]", count, _MAX_COUNT)

    @property
    def malformed(self) -> int:
        """How many payloads claimed to be ours but could not be decoded."""
        return sum(self.errors.values())

    def feed(self, manufacturer_data: Mapping[int, bytes] | bytes) -> TagState | None:
        """Decode the mapping form (or raw 6-byte form); ``None`` if foreign or malformed.

        Input that is neither (a str, None, a number) counts as malformed ``PayloadError``.
        """
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
