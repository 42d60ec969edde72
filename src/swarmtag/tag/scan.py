"""Scanner-side filtering: keep our tags, ignore the rest of the room, count everything.

A robot's radio hears every BLE device nearby. ``ScanFilter.feed`` turns one
advertisement's manufacturer data into a ``TagState``, or ``None`` when it is
foreign or malformed; nothing is ever raised, and the counters say what was
seen so a field engineer can spot a broken tag. The rule:

- **foreign**: no 0xFFFF entry (another company's device), or a 0xFFFF entry
  that is not 4 bytes long (a whole payload other than 6 bytes): 0xFFFF is
  the identifier reserved for tests and internal use, and other devices
  (battery monitors, beacons) advertise under it too, with other lengths;
- **malformed**: a 0xFFFF entry of the tag's length whose values are not a
  tag state (urgency above 9, an unknown status), or input that is not
  manufacturer data at all (not bytes, not a mapping of bytes). A rising
  count means a broken tag (or a foreign device that happens to send 4 bytes).
"""

from __future__ import annotations

from collections import Counter
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Final

from swarmtag.errors import FieldRangeError, ForeignCompanyError, PayloadError, PayloadLengthError
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
    >>> scan.feed({0xFFFF: b"\x01\x02\x03"}) is None  # 0xFFFF, 3 bytes: another device
    True
    >>> (scan.accepted, scan.foreign, scan.malformed)
    (1, 2, 1)
    """

    accepted: int = 0
    foreign: int = 0
    """Adverts of other devices: no 0xFFFF entry, or one of another length than a tag's."""
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
        """How many payloads of a tag's length (or not data at all) could not be decoded."""
        return sum(self.errors.values())

    def feed(self, manufacturer_data: Mapping[int, bytes] | bytes) -> TagState | None:
        """Decode the mapping form (or raw 6-byte form); ``None`` if foreign or malformed.

        A wrong length (``PayloadLengthError``) counts as foreign; input that is
        neither form (a str, None, a number) as malformed ``PayloadError``.
        """
        try:
            if isinstance(manufacturer_data, Mapping):
                state = decode_manufacturer_data(manufacturer_data)
            else:
                state = decode(manufacturer_data)
        except (ForeignCompanyError, PayloadLengthError):
            self.foreign += 1
            return None
        except PayloadError as error:
            self.errors[type(error).__name__] += 1
            return None
        self.accepted += 1
        return state
