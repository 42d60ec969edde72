"""The one place where option and file values are range-checked; each refusal names the field.

Values arrive from TOML files, command-line flags and scripts, so they are
checked at run time rather than trusted to annotations: integers must be
integers (``3.0`` is refused, ``True`` is not a number), numbers may be
written as integers, every number must be finite, and every message says
what was allowed. The error class defaults to ``ConfigError`` (scenario
fields); studies, calibration and the CLI pass their own. The limits shared
by every surface (seeds, run indices) live here too.
"""

from __future__ import annotations

import math
from numbers import Integral, Real
from typing import Final

from swarmtag.errors import ConfigError, SwarmtagError

__all__ = [
    "MAX_RESAMPLES",
    "MAX_RUN_INDEX",
    "MAX_SEED",
    "MAX_WORKERS",
    "check_bool",
    "check_choice",
    "check_int",
    "check_number",
    "check_probability",
    "show",
]

MAX_SEED: Final = 2**63 - 1
"""Largest master seed: a seed is stored as a signed 64-bit integer (results store, logs)."""
MAX_RESAMPLES: Final = 10**9
"""Most bootstrap resamples any option or file accepts; memory is checked against the need first."""
MAX_WORKERS: Final = 256
"""Most worker processes any option accepts (each is a Python process with numpy loaded)."""
MAX_RUN_INDEX: Final = 2**53
"""Largest global run index (run offset plus runs): run ids stay exact in float64 columns."""


def show(value: object) -> str:
    """``repr(value)`` cut to 60 characters; a huge integer by its size (repr would fail).

    >>> show(10**5000), show("x" * 100)[-4:]
    ('an integer of about 5000 digits', "...'")
    """
    if isinstance(value, int) and not isinstance(value, bool) and value.bit_length() > 200:
        return f"an integer of about {round(value.bit_length() * math.log10(2))} digits"
    text = repr(value)
    return text if len(text) <= 60 else text[:57] + "...'"


def _describe_number(low: float | None, high: float | None, *, low_open: bool) -> str:
    if low is not None and high is not None:
        left = "(" if low_open else "["
        return f"a number in {left}{low:g}, {high:g}]"
    if low is not None:
        return f"a number {'>' if low_open else '>='} {low:g}"
    return "a finite number"


def check_number(
    name: str,
    value: object,
    *,
    low: float | None = None,
    high: float | None = None,
    low_open: bool = False,
    error: type[SwarmtagError] = ConfigError,
) -> float:
    """``value`` as a float if it is a finite real in the range, else ``ConfigError``.

    >>> check_number("arena.size", 4, low=0.0, low_open=True)
    4.0
    >>> check_number("arena.size", -1.0, low=0.0, low_open=True)
    Traceback (most recent call last):
    ...
    swarmtag.errors.ConfigError: arena.size: -1.0 is not a number > 0
    """
    allowed = _describe_number(low, high, low_open=low_open)
    if isinstance(value, bool) or not isinstance(value, Real):
        msg = f"{name}: {show(value)} is not {allowed}"
        raise error(msg)
    number = float(value)
    ok = math.isfinite(number)
    if ok and low is not None:
        ok = number > low if low_open else number >= low
    if ok and high is not None:
        ok = number <= high
    if not ok:
        msg = f"{name}: {show(value)} is not {allowed}"
        raise error(msg)
    return number + 0.0  # -0.0 becomes 0.0


def check_probability(
    name: str, value: object, *, error: type[SwarmtagError] = ConfigError
) -> float:
    """A probability in [0, 1].

    >>> check_probability("realism.breakdown", 1.5)
    Traceback (most recent call last):
    ...
    swarmtag.errors.ConfigError: realism.breakdown: 1.5 is not a number in [0, 1]
    """
    return check_number(name, value, low=0.0, high=1.0, error=error)


def check_int(
    name: str,
    value: object,
    *,
    low: int,
    high: int | None = None,
    error: type[SwarmtagError] = ConfigError,
) -> int:
    """``value`` as an int if it is an integer in ``low..high``, else ``ConfigError``.

    >>> check_int("robots", 0, low=1)
    Traceback (most recent call last):
    ...
    swarmtag.errors.ConfigError: robots: 0 is not an integer >= 1
    """
    allowed = f"an integer >= {low}" if high is None else f"an integer in {low}-{high}"
    if isinstance(value, bool) or not isinstance(value, Integral):
        msg = f"{name}: {show(value)} is not {allowed}"
        raise error(msg)
    number = int(value)
    if number < low or (high is not None and number > high):
        msg = f"{name}: {show(value)} is not {allowed}"
        raise error(msg)
    return number


def check_choice(
    name: str,
    value: object,
    choices: tuple[str, ...],
    *,
    error: type[SwarmtagError] = ConfigError,
) -> str:
    """``value`` if it is one of ``choices`` (case-insensitive), in its canonical spelling.

    >>> check_choice("urgency.model", "Static", ("growing", "static"))
    'static'
    """
    if isinstance(value, str) and value.strip().lower() in choices:
        return value.strip().lower()
    msg = f"{name}: {show(value)} is not one of {', '.join(choices)}"
    raise error(msg)


def check_bool(name: str, value: object, *, error: type[SwarmtagError] = ConfigError) -> bool:
    """``value`` if it is a boolean (TOML ``true``/``false``), else ``ConfigError``.

    >>> check_bool("motion.avoid_taken_faces", 1)
    Traceback (most recent call last):
    ...
    swarmtag.errors.ConfigError: motion.avoid_taken_faces: 1 is not true or false
    """
    if isinstance(value, bool):
        return value
    msg = f"{name}: {show(value)} is not true or false"
    raise error(msg)
