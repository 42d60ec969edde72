"""Tag status numbers (SPEC §2.1 byte 3) and their lifecycle meaning."""

from __future__ import annotations

from enum import IntEnum
from typing import Final, NoReturn

from swarmtag.errors import FieldRangeError
from swarmtag.tag._arguments import CheckedEnumType, describe

__all__ = ["TagStatus"]

_CHOICES: Final = "use one of idle, awaiting_pickup, picked_up or 0-2"


class TagStatus(IntEnum, metaclass=CheckedEnumType):
    """The status byte a tag advertises.

    ``IDLE`` → (operator) ``AWAITING_PICKUP`` → (robot lifts) ``PICKED_UP``
    → (robot releases in the drop-off area) ``IDLE``.
    """

    IDLE = 0x00
    AWAITING_PICKUP = 0x01
    PICKED_UP = 0x02

    @classmethod
    def _missing_(cls, value: object) -> NoReturn:
        """Refuse an unknown value with ``FieldRangeError`` (still a ``ValueError``).

        >>> TagStatus(7)
        Traceback (most recent call last):
        ...
        swarmtag.errors.FieldRangeError: status: 7 is not a tag status; use one of ...
        """
        raise FieldRangeError(f"status: {describe(value)} is not a tag status; {_CHOICES}")

    @classmethod
    def parse(cls, value: str | int) -> TagStatus:
        """Read a status from its name in any case or its number (0-2).

        Anything else (a float, None, an unknown name or number) is a ``FieldRangeError``.

        >>> TagStatus.parse("awaiting_pickup")
        <TagStatus.AWAITING_PICKUP: 1>
        >>> TagStatus.parse("2")
        <TagStatus.PICKED_UP: 2>
        """
        given: object = value  # callers without a type checker may pass anything
        if isinstance(given, int) and not isinstance(given, bool):
            return cls(given)
        if isinstance(given, str):
            text = given.strip()
            if text.upper() in cls.__members__:
                return cls[text.upper()]
            if text.isascii() and text.isdigit() and len(text) < 100:
                return cls(int(text))
        raise FieldRangeError(f"status: {describe(value)} is not a tag status; {_CHOICES}")
