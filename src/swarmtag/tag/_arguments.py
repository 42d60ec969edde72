"""Argument checks shared by the tag modules, so bad input meets a typed refusal.

Every public callable of ``swarmtag.tag`` refuses wrong types and out-of-range
values with a ``SwarmtagError`` subclass that names the argument, never with a
raw ``TypeError``/``ValueError`` from deep inside: SPEC §2.1 asks for typed
errors, never a traceback.
"""

from __future__ import annotations

import math
from enum import Enum, EnumType
from typing import Any, TypeVar, cast

from swarmtag.errors import FieldRangeError, SwarmtagError

__all__ = ["CheckedEnumType", "as_bytes", "check_int", "check_type", "describe"]

_T = TypeVar("_T")
_SHOWN: tuple[type, ...] = (int, float, complex, str, bytes, bytearray, type(None))
_MAX_SHOWN = 40
_LONGEST_CLOCK = 1e15
"""Largest clock reading taken, seconds (31 million years: adding a hold stays exact enough)."""


def describe(value: object) -> str:
    """A short description of ``value`` for a message; safe for huge ints and odd objects.

    ``repr`` of an int above 4300 digits raises ``ValueError``, and ``repr`` of a
    container runs arbitrary code, so only simple scalars are shown literally.

    >>> describe(10**5000), describe([1, 2]), describe("x" * 50)
    ('an integer of 16610 bits', 'a list', "'xxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxx...")
    """
    if isinstance(value, int) and value.bit_length() > 64:
        return f"an integer of {value.bit_length()} bits"
    if not isinstance(value, _SHOWN):
        return f"a {type(value).__name__}"
    text = repr(value)
    return text if len(text) <= _MAX_SHOWN else f"{text[: _MAX_SHOWN - 3]}..."


def check_int(name: str, value: object, high: int, low: int = 0) -> int:
    """Return ``value`` if it is an int (not a bool) in ``low..high``; else ``FieldRangeError``."""
    if isinstance(value, bool) or not isinstance(value, int) or not low <= value <= high:
        span = f"{low}-{high}" if low >= 0 else f"{low} to {high}"
        raise FieldRangeError(f"{name}: {describe(value)} is not an integer in {span}")
    return value


def check_clock(name: str, value: object) -> float:
    """``value`` as a float if it is a finite real number (a clock reading), else an error."""
    try:
        seconds = float(value) if isinstance(value, int | float) else math.nan
    except OverflowError:  # an int too large for a float
        seconds = math.nan
    if isinstance(value, bool) or not math.isfinite(seconds) or abs(seconds) > _LONGEST_CLOCK:
        raise FieldRangeError(f"{name}: {describe(value)} is not a finite number of seconds")
    return seconds


def check_type(name: str, value: object, kind: type[_T]) -> _T:
    """Return ``value`` if it is a ``kind``; else ``FieldRangeError`` naming both types."""
    if not isinstance(value, kind):
        raise FieldRangeError(f"{name}: expected a {kind.__name__}, got {type(value).__name__}")
    return value


def as_bytes(name: str, value: object, error: type[SwarmtagError]) -> bytes:
    """``value`` as ``bytes`` if it is bytes, bytearray or memoryview; else ``error``.

    Anything else is refused, not converted: ``bytes(5)`` would silently mean
    five zero bytes and ``bytes("ffff")`` is a ``TypeError``.
    """
    if type(value) is bytes:
        return value
    if isinstance(value, bytes | bytearray | memoryview):
        try:
            return bytes(value)
        except ValueError:  # a released memoryview
            raise error(f"{name}: the memoryview can no longer be read") from None
    raise error(f"{name}: expected bytes, bytearray or memoryview, got {type(value).__name__}")


class CheckedEnumType(EnumType):
    """Enum metaclass that sends huge ints straight to ``_missing_``.

    ``Enum.__new__`` formats an unknown value with ``%r`` before raising what
    ``_missing_`` raised, and that formatting itself fails (``ValueError``) for
    an int above 4300 digits; no member value is that long anyway.
    """

    # Any, as in typeshed's EnumMeta.__call__: mypy still types TagStatus(1) as TagStatus.
    def __call__(cls, value: Any, *args: Any, **kwargs: Any) -> Any:  # noqa: ANN401
        if not args and not kwargs and isinstance(value, int) and value.bit_length() > 64:
            return cast("type[Enum]", cls)._missing_(value)
        return super().__call__(value, *args, **kwargs)
