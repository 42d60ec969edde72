"""The calibration objective: how far simulated KPIs lie from their targets, in CI half-widths.

For a KPI with target ``value`` and CI ``[low, high]`` and an achieved value
``a``, the residual is ``r = (a - value) / h``, where the half-width ``h`` is
the distance from ``value`` to the CI bound on the side of ``a`` (``high -
value`` when ``a >= value``, else ``value - low``), at least
``HALF_WIDTH_FLOOR`` of ``|value|`` (and ``ABSOLUTE_FLOOR``), so that an exact
target such as 840 of 840 deliveries still gives a finite residual. So
``|r| <= 1`` means inside the CI wherever the CI is wider than the floor.
The objective is ``sum(weight * r**2)`` over every KPI of every set-up; a KPI
the simulation leaves undefined (no deliveries, no throughput) adds
``weight * UNDEFINED_PENALTY``. Weight 0 KPIs are reported, never fitted.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from numbers import Real
from typing import Final

from swarmtag._checks import check_instance, check_number, check_sequence, show
from swarmtag.analysis import ConditionRuns, condition_kpis, run_values
from swarmtag.calibration.spec import COUNT_KPIS, KpiTarget, Setup, Targets
from swarmtag.errors import CalibrationError
from swarmtag.io import CarrierLog

__all__ = [
    "ABSOLUTE_FLOOR",
    "HALF_WIDTH_FLOOR",
    "UNDEFINED_PENALTY",
    "Achieved",
    "KpiFit",
    "achieved_kpis",
    "fit_rows",
    "half_width",
    "objective",
    "residual",
]

UNDEFINED_PENALTY: Final = 1e6
"""Objective added per unit weight for a KPI the simulation leaves undefined (r = 1000)."""
HALF_WIDTH_FLOOR: Final = 0.01
"""Smallest half-width, as a fraction of ``|value|``: missing an exact target by 1 % is r = 1."""
ABSOLUTE_FLOOR: Final = 1e-6
"""Smallest half-width at all (for a target value of 0 with a CI of [0, 0])."""

Achieved = Mapping[str, Mapping[str, float | None]]
"""Achieved KPI values per set-up name and KPI name; ``None`` where undefined."""


def half_width(target: KpiTarget, achieved: float) -> float:
    """The CI half-width on the side of ``achieved``, never below the floors.

    >>> t = KpiTarget("p95_latency", value=4979.0, low=4640.0, high=5086.0)
    >>> half_width(t, 5000.0), half_width(t, 4000.0)
    (107.0, 339.0)
    """
    check_instance("target", target, KpiTarget, error=CalibrationError)
    achieved = check_number("achieved", achieved, error=CalibrationError)
    side = target.high - target.value if achieved >= target.value else target.value - target.low
    return max(side, HALF_WIDTH_FLOOR * abs(target.value), ABSOLUTE_FLOOR)


def residual(target: KpiTarget, achieved: float | None) -> float | None:
    """``(achieved - value) / half_width``; ``None`` when ``achieved`` is undefined.

    >>> t = KpiTarget("p95_latency", value=4979.0, low=4640.0, high=5086.0)
    >>> residual(t, 5086.0), residual(t, 4300.0), residual(t, None)
    (1.0, -2.0029498525073746, None)
    """
    check_instance("target", target, KpiTarget, error=CalibrationError)
    given: object = achieved  # checked as what it is, not as annotated
    if given is None:
        return None
    if isinstance(given, bool) or not isinstance(given, Real):
        raise CalibrationError(f"achieved: {show(given)} is not a number or None")
    try:
        number = float(given)
    except OverflowError:  # an integer beyond float range
        return None
    if not math.isfinite(number):
        return None
    return (number - target.value) / half_width(target, number)


@dataclass(frozen=True)
class KpiFit:
    """One row of the fit report: a set-up's KPI target, what was achieved, and its share."""

    setup: str
    target: KpiTarget
    achieved: float | None
    residual: float | None
    """``None`` where the simulation left the KPI undefined."""

    @property
    def inside(self) -> bool:
        """Whether the achieved value lies inside the target's CI."""
        return self.achieved is not None and self.target.low <= self.achieved <= self.target.high

    @property
    def contribution(self) -> float:
        """``weight * r**2``, or ``weight * UNDEFINED_PENALTY`` where undefined (0 for weight 0)."""
        if self.target.weight == 0:
            return 0.0
        if self.residual is None:
            return self.target.weight * UNDEFINED_PENALTY
        return self.target.weight * self.residual**2


def fit_rows(targets: Targets, achieved: Achieved) -> tuple[KpiFit, ...]:
    """Every KPI of every set-up, in file order, with its achieved value and residual."""
    check_instance("targets", targets, Targets, error=CalibrationError)
    check_instance("achieved", achieved, Mapping, error=CalibrationError)  # type: ignore[type-abstract]
    for setup in targets.setups:
        if not isinstance(achieved.get(setup.name), Mapping):
            raise CalibrationError(f"achieved: no KPI values for set-up {setup.name!r}")
    rows = []
    for setup in targets.setups:
        values = achieved[setup.name]
        for target in setup.kpis:
            value = values.get(target.kpi)
            rows.append(KpiFit(setup.name, target, value, residual(target, value)))
    return tuple(rows)


def objective(rows: tuple[KpiFit, ...]) -> float:
    """``sum(weight * r**2)`` over the rows, undefined KPIs counting ``UNDEFINED_PENALTY``.

    >>> t = KpiTarget("pa", value=0.5, low=0.25, high=1.0)
    >>> objective((KpiFit("a", t, 1.0, residual(t, 1.0)), KpiFit("a", t, 0.0, residual(t, 0.0))))
    5.0
    """
    for row in check_sequence("rows", rows, error=CalibrationError):
        check_instance("rows", row, KpiFit, error=CalibrationError)
    return math.fsum(row.contribution for row in rows)


def _defined(value: float | None) -> float | None:
    return None if value is None or not math.isfinite(value) else float(value)


def achieved_kpis(
    log: CarrierLog, *, condition: str, setup: Setup, simulated_runs: int
) -> dict[str, float | None]:
    """The KPIs ``setup`` names, computed on the simulated ``log`` of ``condition``.

    Metrics are looked up by name (``ConditionKPIs.value``); count KPIs
    (``COUNT_KPIS``) are scaled from ``simulated_runs`` to the set-up's runs.
    """
    kpis = condition_kpis(run_values(ConditionRuns.from_log(log, condition)))
    values: dict[str, float | None] = {}
    for target in setup.kpis:
        if target.kpi in COUNT_KPIS:
            count = float(getattr(kpis, target.kpi))
            values[target.kpi] = count * setup.runs / simulated_runs
        else:
            values[target.kpi] = _defined(kpis.value(target.kpi))
    return values
