"""The parameter schema: each scenario parameter declared once, with everything derived from it.

A part of a scenario (``Motion``, ``Timing``, ...) declares each field with
``param``: its default, unit, bounds, a one-line doc and, if the kernel reads
it, its kernel form (``Kernel``: the kernel's name and the conversion into
kernel units, e.g. seconds to whole ticks). ``check_part`` validates every
field from that declaration; ``swarmtag.sim.model.params`` derives the
kernel's ``Params``, the compiled backend's constants and the controller's
configuration from it (docs/architecture.md, "How to add a mechanic").
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterator
from dataclasses import Field, dataclass, field, fields
from typing import TYPE_CHECKING, Any, Final, TypeVar

from swarmtag._checks import check_bool, check_choice, check_int, check_number

if TYPE_CHECKING:
    from _typeshed import DataclassInstance

    from swarmtag.sim.config.scenario import Scenario

__all__ = [
    "AS_IS",
    "CHOICE_INDEX",
    "MICROSECONDS",
    "PER_TICK",
    "RADIANS",
    "TICKS",
    "TICKS_AT_LEAST_ONE",
    "Conversion",
    "Kernel",
    "Spec",
    "check_part",
    "param",
    "seconds_to_ticks",
    "specs",
]

KernelValue = int | float | bool
_T = TypeVar("_T")


@dataclass(frozen=True)
class Conversion:
    """How a scenario value becomes a kernel value: its kernel type, unit and formula."""

    kind: type
    """``int``, ``float`` or ``bool``: the kernel value's type."""
    unit: str
    """The kernel value's unit (``"ticks"``, ``"m per tick"``, ``"as declared"``, ...)."""
    convert: Callable[[Any, Scenario, Spec], KernelValue]


def seconds_to_ticks(seconds: float, tick: float) -> int:
    """A duration in whole ticks, rounded to the nearest tick.

    >>> seconds_to_ticks(1.0, 0.1), seconds_to_ticks(0.3, 0.1), seconds_to_ticks(0.04, 0.1)
    (10, 3, 0)
    """
    return round(seconds / tick)


TICKS: Final = Conversion(int, "ticks", lambda v, s, _: seconds_to_ticks(v, s.tick))
"""Seconds to whole ticks (rounded)."""
TICKS_AT_LEAST_ONE: Final = Conversion(
    int, "ticks", lambda v, s, _: max(1, seconds_to_ticks(v, s.tick))
)
"""Seconds to whole ticks, at least one."""
PER_TICK: Final = Conversion(float, "m per tick", lambda v, s, _: v * s.tick)
"""A speed (per second) to its distance per tick."""
RADIANS: Final = Conversion(float, "rad", lambda v, _s, _: math.radians(v))
"""Degrees to radians."""
MICROSECONDS: Final = Conversion(int, "us", lambda v, _s, _: max(1, round(v * 1e6)))
"""Seconds to whole microseconds (at least one): the tags' advertising grid."""
CHOICE_INDEX: Final = Conversion(int, "index", lambda v, _s, spec: spec.choices.index(v))
"""A named choice to its index among the declared choices."""


def _as_is(kind: type) -> Conversion:
    return Conversion(kind, "as declared", lambda v, _s, _: v)


AS_IS: Final[dict[type, Conversion]] = {kind: _as_is(kind) for kind in (int, float, bool)}
"""The value unchanged, by its type."""


@dataclass(frozen=True)
class Kernel:
    """A parameter's kernel form: its name in ``Params`` and how it is converted."""

    name: str
    conversion: Conversion | None = None
    """None: the value as it is (``AS_IS`` of the field's type)."""
    controller: bool = False
    """Also part of the controller's configuration (``robot.ControllerConfig``)."""


@dataclass(frozen=True)
class Spec:
    """One scenario parameter's declaration (besides its name, type and default)."""

    unit: str
    doc: str
    low: float | None = None
    high: float | None = None
    low_open: bool = False
    choices: tuple[str, ...] = ()
    kernel: Kernel | None = None


_KEY: Final = "swarmtag"


def param(
    default: _T,
    *,
    unit: str,
    doc: str,
    low: float | None = None,
    high: float | None = None,
    low_open: bool = False,
    choices: tuple[str, ...] = (),
    kernel: Kernel | None = None,
) -> _T:
    """A dataclass field declaring a scenario parameter (see the module docstring)."""
    spec = Spec(unit, doc, low, high, low_open, choices, kernel)
    declared: _T = field(default=default, metadata={_KEY: spec})
    return declared


def specs(part: DataclassInstance | type[DataclassInstance]) -> Iterator[tuple[Field[Any], Spec]]:
    """The declared parameters of a part class (or instance), in declaration order."""
    for item in fields(part):
        spec = item.metadata.get(_KEY)
        if isinstance(spec, Spec):
            yield item, spec


def _checked(name: str, kind: str, value: object, spec: Spec) -> object:
    """``value`` validated against ``spec`` as the declared type ``kind``."""
    if kind == "bool":
        return check_bool(name, value)
    if kind == "str":
        return check_choice(name, value, spec.choices)
    if kind == "int":
        low = -(2**63) if spec.low is None else int(spec.low)
        high = None if spec.high is None else int(spec.high)
        return check_int(name, value, low=low, high=high)
    return check_number(name, value, low=spec.low, high=spec.high, low_open=spec.low_open)


def check_part(part: DataclassInstance, prefix: str) -> None:
    """Validate and normalise every declared field of ``part`` (names as ``prefix.field``)."""
    for item, spec in specs(part):
        kind = item.type if isinstance(item.type, str) else item.type.__name__
        value = _checked(f"{prefix}.{item.name}", kind, getattr(part, item.name), spec)
        object.__setattr__(part, item.name, value)
