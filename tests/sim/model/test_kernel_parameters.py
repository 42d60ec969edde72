"""One parameter schema: Params, the compiled constants and the controller config derive from it."""

from __future__ import annotations

from dataclasses import dataclass, fields, replace

import pytest

from swarmtag.errors import ConfigError
from swarmtag.policy import Urgency
from swarmtag.robot.config import ControllerConfig
from swarmtag.sim import Scenario, make_params
from swarmtag.sim.config.parts import MAX_DURATION, Timing
from swarmtag.sim.config.schema import TICKS, Kernel, param, specs
from swarmtag.sim.fast._constants import PARAMETERS, Constants
from swarmtag.sim.fast._extras import EXTRAS
from swarmtag.sim.fast._layout import constants_of
from swarmtag.sim.model._fields import ControllerFields, ParamFields
from swarmtag.sim.model.kernel_parameters import (
    PARTS,
    kernel_parameters,
    render,
    render_constants,
    render_fields,
)


def test_the_generated_records_are_up_to_date():
    for path, text in render().items():
        assert path.read_text(encoding="utf-8") == text, f"{path.name} is stale: run make generate"


def test_every_kernel_parameter_is_declared_once_and_reaches_every_record():
    names = [parameter.name for parameter in kernel_parameters()]
    assert len(names) == len(set(names))
    assert [item.name for item in fields(ParamFields)] == names
    assert list(PARAMETERS) == names
    assert list(Constants._fields) == names + [name for name, _, _ in EXTRAS]
    controller = [p.name for p in kernel_parameters() if p.controller]
    assert [item.name for item in fields(ControllerFields)] == controller


def test_params_constants_and_controller_config_agree_on_every_shared_value():
    scenario = replace(Scenario.default(5, 10, profile="lab"), ticks=900)
    params = make_params(scenario, Urgency(alpha=0.7))
    constants = constants_of(params)
    config = ControllerConfig.from_params(params)
    for name in PARAMETERS:
        assert getattr(constants, name) == getattr(params, name), name
    for item in fields(ControllerFields):
        assert getattr(config, item.name) == getattr(params, item.name), item.name


@dataclass(frozen=True, slots=True)
class TimingWithCharge(Timing):
    """The docs' worked example: a new mechanic's parameter (a charging stop), declared once."""

    charge: float = param(
        2.0, unit="s", doc="Time a robot spends charging after a delivery.", low=0.0,
        high=MAX_DURATION, kernel=Kernel("charge_ticks", TICKS, controller=True),
    )  # fmt: skip


def test_worked_example_one_declaration_gives_validation_params_constants_and_config():
    parts = tuple((name, TimingWithCharge if cls is Timing else cls) for name, cls in PARTS)
    with pytest.raises(ConfigError, match=r"timing\.charge: -1\.0 is not a number in \[0, "):
        TimingWithCharge(charge=-1.0)
    declared = {item.name: spec for item, spec in specs(TimingWithCharge)}
    assert declared["charge"].unit == "s"
    charge = next(p for p in kernel_parameters(parts) if p.name == "charge_ticks")
    assert (charge.kind, charge.unit, charge.controller) == (int, "ticks", True)
    scenario = replace(Scenario(), tick=0.1, timing=TimingWithCharge(charge=2.0))
    assert charge.derive(scenario) == 20
    generated = render_fields(parts)
    assert generated.count("    charge_ticks: int\n") == 2  # ParamFields and ControllerFields
    assert "    charge_ticks: int\n" in render_constants(EXTRAS, parts)
    assert "charge_ticks" not in render_fields()
