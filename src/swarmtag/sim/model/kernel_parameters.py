"""Every kernel parameter, derived from the scenario schema, and the records generated from it.

A kernel parameter is either one scenario field's kernel form (declared with
the field: ``param(..., kernel=Kernel(...))`` in ``swarmtag.sim.config``) or
one of the few that combine several fields, listed in ``DERIVED`` below.
From this one list come, by code:

- ``Params`` (``swarmtag.sim.model.params``): every kernel parameter;
- the compiled backend's ``Constants`` (``swarmtag.sim.fast._constants``):
  every scalar of ``Params`` plus the backend's own derived values;
- the controller's configuration (``swarmtag.robot.ControllerConfig``): the
  parameters marked ``controller``.

The typed records live in generated modules (``_fields.py`` here and
``fast/_constants.py``) so that mypy and numba see plain classes; run
``make generate`` after changing the schema
(``tests/sim/model/test_kernel_parameters.py`` fails while they are stale).
"""

from __future__ import annotations

import math
import sys
import textwrap
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any, Final

from swarmtag.errors import ConfigError
from swarmtag.sim.config.scenario import PARTS, Scenario
from swarmtag.sim.config.schema import (
    AS_IS,
    Conversion,
    Kernel,
    KernelValue,
    Spec,
    seconds_to_ticks,
    specs,
)
from swarmtag.sim.config.warehouse import floor_of

if TYPE_CHECKING:
    from _typeshed import DataclassInstance

__all__ = ["DERIVED", "PARTS", "KernelParameter", "derive_all", "kernel_parameters", "render"]


@dataclass(frozen=True)
class KernelParameter:
    """One parameter as the kernel reads it: name, type, unit, doc, how it is derived."""

    name: str
    kind: type
    unit: str
    doc: str
    derive: Callable[[Scenario], KernelValue]
    controller: bool = False


def _part(scenario: Scenario, name: str) -> DataclassInstance:
    """The part of ``scenario`` named ``name`` (the arena after scaling)."""
    return scenario.area if name == "arena" else getattr(scenario, name)


def _pursuit_timeout(scenario: Scenario) -> int:
    """The pursuit timeout in ticks: at least one tick, else a ``ConfigError``."""
    timing = scenario.timing
    ticks = seconds_to_ticks(timing.pursuit_timeout, scenario.tick)
    if ticks < 1:
        msg = f"timing.pursuit_timeout: {timing.pursuit_timeout!r} s is shorter than one tick"
        raise ConfigError(msg)
    return ticks


def _turn(scenario: Scenario) -> float:
    """The largest turn in one tick, radians (at most half a turn)."""
    return math.radians(min(scenario.motion.turn_rate * scenario.tick, 180.0))


def _width(scenario: Scenario) -> float:
    """The floor's extent in x: the arena's side, or the warehouse map's width."""
    if scenario.warehouse is None:
        return scenario.area.size
    return floor_of(scenario.warehouse).width


def _height(scenario: Scenario) -> float:
    """The floor's extent in y: the arena's side, or the warehouse map's height."""
    if scenario.warehouse is None:
        return scenario.area.size
    return floor_of(scenario.warehouse).height


def _horizon(scenario: Scenario) -> float:
    """T in ticks: the run (growing), the static horizon, or a warehouse's urgency window."""
    if scenario.warehouse is not None:
        return scenario.warehouse.urgency_window / scenario.tick
    if scenario.urgency.model == "growing":
        return float(scenario.ticks)
    return scenario.urgency.static_horizon / scenario.tick


def _walk_turn_ticks(scenario: Scenario) -> int:
    """Ticks between a walking robot's turns (0: never)."""
    interval = scenario.walk.turn_interval
    return max(1, seconds_to_ticks(interval, scenario.tick)) if interval > 0 else 0


def _look_ticks(scenario: Scenario) -> int:
    """Ticks of a look round before choosing (0: none)."""
    look = scenario.camera.look_around
    return max(1, seconds_to_ticks(look, scenario.tick)) if look > 0 else 0


def _seek_margin(scenario: Scenario) -> float:
    """One standard deviation of a running RSSI estimate, as a factor (BLE-led search).

    The smoothing's running mean of independent samples keeps
    ``w / (2 - w)`` of their variance; a seeker takes a rise by less than
    that for noise.
    """
    radio = scenario.radio
    sigma = radio.shadowing / (10.0 * radio.path_loss_exponent)
    weight = radio.smoothing
    return float(10.0 ** (sigma * math.sqrt(weight / (2.0 - weight))))


DERIVED: Final[tuple[KernelParameter, ...]] = (
    KernelParameter("robots", int, "", "Robots per run.", lambda s: s.robots),
    KernelParameter(
        "carriers", int, "", "Carriers per run (a warehouse's orders).", lambda s: s.carriers
    ),
    KernelParameter(
        "arena",
        float,
        "m",
        "The floor's extent in x (the arena's side, or the map's width).",
        _width,
        controller=True,
    ),
    KernelParameter(
        "arena_height",
        float,
        "m",
        "The floor's extent in y (``arena`` in the lab; the map's height).",
        _height,
    ),
    KernelParameter(
        "dropoff_left",
        float,
        "m",
        "The drop-off area is ``x >= dropoff_left`` (lab arena).",
        lambda s: s.area.size - s.area.dropoff_width,
        controller=True,
    ),
    KernelParameter(
        "transport_x",
        float,
        "m",
        "x of a transport goal: the middle of the drop-off area.",
        lambda s: s.area.size - s.area.dropoff_width / 2,
        controller=True,
    ),
    KernelParameter(
        "robot_radius",
        float,
        "m",
        "Half the robot's diameter.",
        lambda s: s.bodies.robot_diameter / 2,
        controller=True,
    ),
    KernelParameter(
        "carrier_half",
        float,
        "m",
        "Half the carrier's side.",
        lambda s: s.bodies.carrier_size / 2,
        controller=True,
    ),
    KernelParameter(
        "predock_offset",
        float,
        "m",
        "Carrier centre to predock point: half the carrier side plus the predock distance.",
        lambda s: s.bodies.carrier_size / 2 + s.motion.predock_distance,
        controller=True,
    ),
    KernelParameter(
        "turn_cos",
        float,
        "",
        "Cosine of the largest turn in one tick.",
        lambda s: math.cos(_turn(s)),
    ),
    KernelParameter(
        "turn_sin", float, "", "Sine of the largest turn in one tick.", lambda s: math.sin(_turn(s))
    ),
    KernelParameter(
        "split",
        bool,
        "",
        "Split perception (radio and camera apart, docs/simulator.md) rather than one disc.",
        lambda s: s.perception == "split",
    ),
    KernelParameter(
        "camera_range",
        float,
        "m",
        "The camera's range (its 50 % distance with a fade), times the perception factor.",
        lambda s: s.camera.range * s.perception_factor,
    ),
    KernelParameter(
        "camera_fade",
        float,
        "m",
        "Width of the camera's detection ramp (0: a hard disc), times the perception factor.",
        lambda s: s.camera.fade * s.perception_factor,
    ),
    KernelParameter(
        "detection_radius",
        float,
        "m",
        "Disc perception: the detection radius; split: the camera range (as far as robots see).",
        lambda s: (
            s.camera.range * s.perception_factor if s.perception == "split" else s.detection_radius
        ),
        controller=True,
    ),
    KernelParameter(
        "camera_far",
        float,
        "m",
        "Beyond this no carrier is seen: the camera range plus half its fade.",
        lambda s: (s.camera.range + s.camera.fade / 2) * s.perception_factor,
    ),
    KernelParameter(
        "rssi_sigma",
        float,
        "",
        "log10 of the RSSI distance's error factor, its standard deviation: shadowing / (10 n).",
        lambda s: s.radio.shadowing / (10.0 * s.radio.path_loss_exponent),
    ),
    KernelParameter(
        "seek_margin",
        float,
        "",
        "A seeker tumbles when its tag's estimate exceeds the leg's least by this factor.",
        _seek_margin,
        controller=True,
    ),
    KernelParameter(
        "tick_us",
        int,
        "us",
        "The tick in whole microseconds: tags advertise on this grid.",
        lambda s: max(1, round(s.tick * 1e6)),
    ),
    KernelParameter(
        "walk_turn_ticks",
        int,
        "ticks",
        "A walking robot turns its heading every so many ticks (0: never).",
        _walk_turn_ticks,
        controller=True,
    ),
    KernelParameter(
        "look_ticks",
        int,
        "ticks",
        "A robot that sees a candidate stands and turns this many ticks before choosing (0: no).",
        _look_ticks,
        controller=True,
    ),
    KernelParameter(
        "walk_curve",
        float,
        "rad",
        "A curved walk's largest turn per tick: walk.curve times the tick (0: no curve).",
        lambda s: math.radians(s.walk.curve) * s.tick,
        controller=True,
    ),
    KernelParameter(
        "time_scale",
        float,
        "",
        "Event-log time units per tick: 1 (logs in ticks) or ``tick`` (seconds).",
        lambda s: s.tick if s.time_unit == "s" else 1.0,
    ),
    KernelParameter(
        "timeout_ticks",
        int,
        "ticks",
        "A pursuit (predock, dock, centre) gives up after this long.",
        _pursuit_timeout,
        controller=True,
    ),
    KernelParameter("run_ticks", int, "ticks", "Ticks a run lasts at most.", lambda s: s.run_ticks),
    KernelParameter(
        "growing",
        bool,
        "",
        "Growing urgency model (else static).",
        lambda s: s.urgency.model == "growing",
    ),
    KernelParameter(
        "horizon",
        float,
        "ticks",
        "T: the run length (growing), the static horizon, or a warehouse's urgency window.",
        _horizon,
    ),
)
"""Kernel parameters that combine several scenario fields (or top-level ones)."""


def _from_field(part: str, name: str, kind: type, spec: Spec, kernel: Kernel) -> KernelParameter:
    """The kernel parameter of field ``part.name``, declared with ``spec``."""
    conversion: Conversion = kernel.conversion or AS_IS[kind]

    def derive(scenario: Scenario) -> KernelValue:
        return conversion.convert(getattr(_part(scenario, part), name), scenario, spec)

    doc = f"{spec.doc} (``{part}.{name}``)"
    return KernelParameter(
        kernel.name, conversion.kind, conversion.unit, doc, derive, kernel.controller
    )


_KINDS: Final = {"int": int, "float": float, "bool": bool, "str": str}


def kernel_parameters(
    parts: tuple[tuple[str, type], ...] = PARTS,
) -> tuple[KernelParameter, ...]:
    """Every kernel parameter: ``DERIVED``, then each part's fields with a kernel form."""
    found = list(DERIVED)
    for part, cls in parts:
        for item, spec in specs(cls):
            if spec.kernel is not None:
                kind = _KINDS[item.type] if isinstance(item.type, str) else item.type
                found.append(_from_field(part, item.name, kind, spec, spec.kernel))
    return tuple(found)


def derive_all(scenario: Scenario) -> dict[str, Any]:
    """Every kernel parameter's value for ``scenario``, by name."""
    return {parameter.name: parameter.derive(scenario) for parameter in kernel_parameters()}


# The generated modules -------------------------------------------------------------------

_HEADER: Final = '''"""{title}

Generated by ``make generate`` (``swarmtag.sim.model.kernel_parameters``) from the
parameter schema: do not edit (docs/architecture.md, "How to add a mechanic").
"""

'''


def _doc(text: str) -> list[str]:
    lines = textwrap.wrap(text, 88)
    if len(lines) == 1:
        return [f'    """{lines[0]}"""']
    return ['    """' + lines[0], *(f"    {line}" for line in lines[1:]), '    """']


def _field_lines(parameter: KernelParameter) -> list[str]:
    unit = f" [{parameter.unit}]" if parameter.unit and parameter.unit != "as declared" else ""
    return [f"    {parameter.name}: {parameter.kind.__name__}", *_doc(parameter.doc + unit)]


def _dataclass(name: str, doc: str, parameters: list[KernelParameter]) -> list[str]:
    lines = ["@dataclass(frozen=True, eq=False)", f"class {name}:", f'    """{doc}"""', ""]
    for parameter in parameters:
        lines += _field_lines(parameter)
    return lines


def render_fields(parts: tuple[tuple[str, type], ...] = PARTS) -> str:
    """The text of ``sim/model/_fields.py``: the typed parameter records."""
    every = list(kernel_parameters(parts))
    lines = [
        "from __future__ import annotations",
        "",
        "from dataclasses import dataclass",
        "",
        '__all__ = ["ControllerFields", "ParamFields"]',
        "",
        "",
        *_dataclass("ParamFields", "Every kernel parameter (``Params`` adds the rest).", every),
        "",
        "",
        *_dataclass(
            "ControllerFields",
            "The parameters a controller is configured with (``robot.ControllerConfig``).",
            [p for p in every if p.controller],
        ),
    ]  # fmt: skip
    title = "The kernel's parameter records, typed: one field per kernel parameter."
    return _HEADER.format(title=title) + "\n".join(lines) + "\n"


def render_constants(
    extras: tuple[tuple[str, str, str], ...], parts: tuple[tuple[str, type], ...] = PARTS
) -> str:
    """The text of ``sim/fast/_constants.py``: every scalar parameter, then the backend's own."""
    lines = [
        "from __future__ import annotations",
        "",
        "from typing import NamedTuple",
        "",
        "import numpy as np",
        "from numpy.typing import NDArray",
        "",
        '__all__ = ["PARAMETERS", "Constants"]',
        "",
        "",
        "class Constants(NamedTuple):",
        '    """``Params`` as the numbers the compiled kernel reads, and its own values."""',
        "",
    ]
    names = []
    for parameter in kernel_parameters(parts):
        names.append(parameter.name)
        lines += _field_lines(parameter)
    for name, annotation, doc in extras:
        lines += [f"    {name}: {annotation}", *_doc(doc)]
    lines += ["", "", "PARAMETERS = (", *(f'    "{name}",' for name in names), ")"]
    lines.append('"""The fields copied from ``Params``; the rest are the backend\'s own."""')
    title = "The compiled kernel's constants: every scalar kernel parameter, then its own."
    return _HEADER.format(title=title) + "\n".join(lines) + "\n"


def render() -> dict[Path, str]:
    """Every generated module's path and text."""
    from swarmtag.sim.fast._extras import EXTRAS  # noqa: PLC0415 - the backend's own fields

    sim = Path(__file__).resolve().parents[1]
    return {
        sim / "model" / "_fields.py": render_fields(),
        sim / "fast" / "_constants.py": render_constants(EXTRAS),
    }


def main() -> int:
    """Write the generated modules; say which changed."""
    for path, text in render().items():
        if not path.exists() or path.read_text(encoding="utf-8") != text:
            path.write_text(text, encoding="utf-8")
            sys.stdout.write(f"wrote {path.name}\n")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
