"""Tag status numbers (SPEC §2.1 byte 3) and their lifecycle meaning."""

from __future__ import annotations

from enum import IntEnum

from swarmtag.errors import FieldRangeError

__all__ = ["TagStatus"]


class TagStatus(IntEnum):
    """The status byte a tag advertises.

    ``IDLE`` → (operator) ``AWAITING_PICKUP`` → (robot lifts) ``PICKED_UP``
    → (robot releases in the drop-off area) ``IDLE``.
    """

    IDLE = 0x00
    AWAITING_PICKUP = 0x01
    PICKED_UP = 0x02

    @classmethod
    def parse(cls, value: str | int) -> TagStatus:
        """Read a status from its name in any case or its number (0-2).

        >>> TagStatus.parse("awaiting_pickup")
        <TagStatus.AWAITING_PICKUP: 1>
        >>> TagStatus.parse("2")
        <TagStatus.PICKED_UP: 2>
        """
        if isinstance(value, int) and not isinstance(value, bool):
            number: int | None = value
        else:
            text = str(value).strip()
            number = int(text) if text.isdigit() else None
            if number is None:
                try:
                    return cls[text.upper()]
                except KeyError:
                    pass
        if number is not None:
            try:
                return cls(number)
            except ValueError:
                pass
        names = ", ".join(member.name.lower() for member in cls)
        raise FieldRangeError(
            f"status: {value!r} is not a tag status; use one of {names} or 0-{len(cls) - 1}"
        )
