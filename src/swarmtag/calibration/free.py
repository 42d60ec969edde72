"""Free parameters: the scenario keys a calibration fits, each within stated bounds.

``NAME=LO:HI`` searches ``[LO, HI]`` uniformly, ``NAME=LO:HI:log`` uniformly
in ``log`` (for scales such as a tick or a duration, where 0.05 -> 0.1 is as
big a step as 0.5 -> 1). The search works in the unit cube; ``from_unit``
and ``to_unit`` map between it and the parameter.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Final

from swarmtag._checks import check_sequence, check_text
from swarmtag.errors import CalibrationError

__all__ = ["MAX_FREE", "FreeParameter", "parse_free", "parse_free_list", "round_significant"]

MAX_FREE: Final = 8
"""Most free parameters of one calibration (the search needs ~10x as many evaluations)."""
SCALES: Final = ("linear", "log")


def round_significant(value: float, digits: int) -> float:
    """``value`` rounded to ``digits`` significant digits.

    >>> round_significant(0.0123456, 4), round_significant(98765.0, 2)
    (0.01235, 99000.0)
    """
    return float(f"{value:.{digits}g}")


@dataclass(frozen=True)
class FreeParameter:
    """A scenario key (dotted for tables: ``timing.dock``) fitted within ``[low, high]``.

    >>> p = FreeParameter("tick", 0.01, 1.0, log=True)
    >>> round(p.from_unit(0.5), 12), p.to_unit(0.1)
    (0.1, 0.5)
    """

    key: str
    low: float
    high: float
    log: bool = False

    def __post_init__(self) -> None:
        where = f"--free {self.key}"
        for bound in (self.low, self.high):
            if isinstance(bound, bool) or not isinstance(bound, int | float):
                raise CalibrationError(f"{where}: bound {bound!r} is not a number")
            if not math.isfinite(bound):
                raise CalibrationError(f"{where}: bound {bound!r} is not finite")
        if not self.low < self.high:
            msg = f"{where}: the bounds {self.low:g}:{self.high:g} are empty (need LO < HI)"
            raise CalibrationError(msg)
        if self.log and self.low <= 0:
            msg = f"{where}: a log scale needs LO > 0 (got {self.low:g})"
            raise CalibrationError(msg)

    @property
    def spec(self) -> str:
        """The ``NAME=LO:HI[:log]`` text of this parameter (floats as Python's ``repr``)."""
        return f"{self.key}={self.low!r}:{self.high!r}" + (":log" if self.log else "")

    def from_unit(self, u: float) -> float:
        """The parameter value at ``u`` in [0, 1] (log-uniform for a log scale)."""
        u = min(1.0, max(0.0, float(u)))
        if u in (0.0, 1.0):  # the bounds exactly, whatever exp(log(x)) rounds to
            return self.low if u == 0.0 else self.high
        if self.log:
            low, high = math.log(self.low), math.log(self.high)
            return min(self.high, max(self.low, math.exp(low + u * (high - low))))
        return min(self.high, max(self.low, self.low + u * (self.high - self.low)))

    def to_unit(self, value: float) -> float:
        """The position of ``value`` in [0, 1] (the inverse of ``from_unit``)."""
        if self.log:
            low, high = math.log(self.low), math.log(self.high)
            return (math.log(value) - low) / (high - low)
        return (value - self.low) / (self.high - self.low)

    def clamp_round(self, value: float, digits: int) -> float:
        """``value`` rounded to ``digits`` significant digits, kept within the bounds."""
        rounded = round_significant(value, digits)
        return min(self.high, max(self.low, rounded))


def parse_free(text: str) -> FreeParameter:
    """``NAME=LO:HI`` or ``NAME=LO:HI:log`` as a ``FreeParameter``; one clear line otherwise.

    >>> parse_free("timing.dock=0.5:5:log")
    FreeParameter(key='timing.dock', low=0.5, high=5.0, log=True)
    >>> parse_free("tick=0.2:0.1")
    Traceback (most recent call last):
    ...
    swarmtag.errors.CalibrationError: --free tick: the bounds 0.2:0.1 are empty (need LO < HI)
    """
    check_text("--free", text, error=CalibrationError)
    key, equals, rest = text.partition("=")
    key = key.strip()
    parts = [part.strip() for part in rest.split(":")]
    if not equals or not key or len(parts) not in (2, 3):
        msg = f"--free: {text!r} is not NAME=LO:HI or NAME=LO:HI:log (e.g. timing.dock=0.5:5:log)"
        raise CalibrationError(msg)
    scale = parts[2] if len(parts) == 3 else "linear"
    if scale not in SCALES:
        msg = f"--free {key}: scale {scale!r} is not 'log' (leave it out for a linear scale)"
        raise CalibrationError(msg)
    bounds = []
    for part in parts[:2]:
        try:
            bounds.append(float(part))
        except ValueError:
            raise CalibrationError(f"--free {key}: bound {part!r} is not a number") from None
    return FreeParameter(key, bounds[0], bounds[1], log=scale == "log")


def parse_free_list(texts: Sequence[str]) -> tuple[FreeParameter, ...]:
    """Several ``--free`` specs; refuses none, duplicates and more than ``MAX_FREE``."""
    texts = check_sequence("--free", texts, error=CalibrationError)
    if not texts:
        msg = "no free parameters: give --free NAME=LO:HI (or a target file's calibration.free)"
        raise CalibrationError(msg)
    parameters = tuple(parse_free(text) for text in texts)
    keys = [parameter.key for parameter in parameters]
    repeated = sorted({key for key in keys if keys.count(key) > 1})
    if repeated:
        raise CalibrationError(f"--free {repeated[0]}: given twice")
    if len(parameters) > MAX_FREE:
        msg = f"--free: {len(parameters)} free parameters; at most {MAX_FREE} can be fitted at once"
        raise CalibrationError(msg)
    return parameters
