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
import os
from collections.abc import Sequence
from numbers import Integral, Real
from typing import TYPE_CHECKING, Any, Final, TypeVar

from swarmtag.errors import ConfigError, SwarmtagError

if TYPE_CHECKING:
    from numpy.typing import NDArray

__all__ = [
    "MAX_RESAMPLES",
    "MAX_RUN_INDEX",
    "MAX_SEED",
    "MAX_WORKERS",
    "check_array",
    "check_bool",
    "check_choice",
    "check_instance",
    "check_int",
    "check_number",
    "check_path_value",
    "check_probability",
    "check_sequence",
    "check_text",
    "show",
]

T = TypeVar("T")

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
    try:
        number = float(value)
    except OverflowError:  # an integer beyond float range
        number = math.inf
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


def check_instance(
    name: str, value: object, kind: type[T], *, error: type[SwarmtagError] = ConfigError
) -> T:
    """``value`` if it is a ``kind``: a public function's object argument, checked at the entry.

    >>> check_instance("runs", 1.5, dict)
    Traceback (most recent call last):
    ...
    swarmtag.errors.ConfigError: runs: 1.5 is not a dict
    """
    if isinstance(value, kind):
        return value
    msg = f"{name}: {show(value)} is not a {kind.__name__}"
    raise error(msg)


def check_text(name: str, value: object, *, error: type[SwarmtagError] = ConfigError) -> str:
    """``value`` if it is a string (a name, a condition, a spec), else ``error``.

    >>> check_text("condition", 3)
    Traceback (most recent call last):
    ...
    swarmtag.errors.ConfigError: condition: 3 is not a string
    """
    if isinstance(value, str):
        return value
    msg = f"{name}: {show(value)} is not a string"
    raise error(msg)


def check_sequence(
    name: str, value: object, *, error: type[SwarmtagError] = ConfigError
) -> Sequence[Any]:
    """``value`` as a tuple if it is a list, tuple or 1-D array (a string is no sequence here).

    >>> check_sequence("levels", 5)
    Traceback (most recent call last):
    ...
    swarmtag.errors.ConfigError: levels: 5 is not a list or tuple
    """
    if isinstance(value, list | tuple | range):
        return tuple(value)
    if getattr(value, "ndim", None) == 1 and hasattr(value, "tolist"):
        return tuple(value.tolist())  # a 1-D numpy array
    msg = f"{name}: {show(value)} is not a list or tuple"
    raise error(msg)


def check_array(
    name: str,
    value: object,
    *,
    integer: bool = False,
    nan: bool = False,
    low: float | None = None,
    error: type[SwarmtagError] = ConfigError,
) -> NDArray[Any]:
    """``value`` as a 1-D float64 (or int64) array of finite numbers, each ``>= low``.

    ``nan=True`` lets NaN through (an undefined value), never an infinity.
    Checked once at a public entry; the kernels behind it trust the array.

    >>> check_array("x", [1.0, float("inf")])
    Traceback (most recent call last):
    ...
    swarmtag.errors.ConfigError: x: [1.0, inf] holds a value that is not a finite number
    """
    import numpy as np  # noqa: PLC0415 - the scenario checks above never need numpy

    kind = "integers" if integer else "numbers"
    try:
        array = np.asarray(value)
        numbers = array.astype(np.float64) if array.dtype.kind in "iuf" else None
    except (TypeError, ValueError, OverflowError):
        numbers = None
    if numbers is None or numbers.ndim != 1:
        msg = f"{name}: {show(value)} is not a 1-D sequence of {kind}"
        raise error(msg)
    finite = np.isfinite(numbers)
    if not (finite | np.isnan(numbers) if nan else finite).all():
        msg = f"{name}: {show(value)} holds a value that is not a finite number"
        raise error(msg)
    if integer and not (np.isnan(numbers) | (numbers == np.round(numbers))).all():
        msg = f"{name}: {show(value)} holds a value that is not an integer"
        raise error(msg)
    if low is not None and (numbers < low).any():
        msg = f"{name}: {show(value)} holds a value below {low:g}"
        raise error(msg)
    if not integer:
        return numbers
    if (np.abs(numbers) > 2**62).any():
        msg = f"{name}: {show(value)} holds an integer too large"
        raise error(msg)
    return array.astype(np.int64)


def check_path_value(name: str, value: object, *, error: type[SwarmtagError] = ConfigError) -> str:
    """``value`` as a path string if it is a ``str`` or ``os.PathLike`` naming something.

    >>> check_path_value("baseline", 3)
    Traceback (most recent call last):
    ...
    swarmtag.errors.ConfigError: baseline: 3 is not a path
    """
    text = os.fspath(value) if isinstance(value, str | os.PathLike) else None
    if not isinstance(text, str) or not text or "\0" in text:
        msg = f"{name}: {show(value)} is not a path"
        raise error(msg)
    return text
