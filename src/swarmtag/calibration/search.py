"""The search: a scrambled Sobol design over the bounds, then bounded Nelder-Mead from its best.

Under common random numbers the objective is deterministic, but it is rough:
a parameter change moves discrete events (a pickup one tick earlier, a
carrier delivered or not), so the objective is piecewise constant with small
jumps and has no useful gradient. A space-filling design finds the right
basin without assuming smoothness, and Nelder-Mead, which uses only
comparisons of values, refines it. Both run in the unit cube (``[0, 1]`` per
parameter, log-uniform for log-scaled ones, ``FreeParameter.from_unit``).

The budget counts distinct points visited; a point Nelder-Mead revisits is
not evaluated again. The design gets half the budget, rounded down to a
power of two (Sobol points are balanced in powers of two), at least one
point; Nelder-Mead gets the rest. The search is a pure function of the
objective, the dimension, the budget and the seed, so a rerun visits the
same points in the same order.
"""

from __future__ import annotations

import importlib
import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any, Final

import numpy as np
from numpy.typing import NDArray

from swarmtag._checks import MAX_SEED, check_int, show
from swarmtag.errors import CalibrationError

__all__ = ["SIMPLEX_STEP", "SearchResult", "SearchStep", "design_size", "search"]

MAX_DIMS: Final = 100
"""Most dimensions one search takes (a calibration fits at most ``MAX_FREE``)."""
MAX_BUDGET: Final = 100_000
"""Most points one search may evaluate (a calibration spends at most ``MAX_EVALUATIONS``)."""
SIMPLEX_STEP: Final = 0.1
"""Edge of Nelder-Mead's first simplex, as a fraction of each parameter's range."""
XATOL: Final = 1e-3
"""Nelder-Mead stops when the simplex is smaller than this (unit cube) ..."""
FATOL: Final = 1e-3
"""... and the objective varies by less than this over it."""

BatchObjective = Callable[[NDArray[np.float64]], Sequence[float]]
"""Objective values of a batch of points ``(n, d)`` in the unit cube, in their order."""


@dataclass(frozen=True)
class SearchStep:
    """One evaluated point: which phase asked for it, where it lies (unit cube), its value."""

    phase: str
    """``"design"`` or ``"nelder-mead"``."""
    unit: tuple[float, ...]
    objective: float


@dataclass(frozen=True)
class SearchResult:
    """The best point found (unit cube), its objective, and every step in order."""

    best: tuple[float, ...]
    objective: float
    steps: tuple[SearchStep, ...]
    design: int
    """Points of the Sobol design."""
    message: str
    """How Nelder-Mead ended (its own message, or that the budget was used up)."""

    @property
    def evaluations(self) -> int:
        """Distinct points evaluated."""
        return len(self.steps)


class _BudgetUsed(Exception):
    """Raised inside the objective to stop Nelder-Mead when the budget is used up."""


def design_size(budget: int) -> int:
    """Points of the Sobol design for ``budget`` evaluations: half, as a power of two, >= 1.

    >>> [design_size(n) for n in (1, 2, 6, 32, 100)]
    [1, 1, 2, 16, 32]
    """
    half = max(1, budget // 2)
    return 1 << (half.bit_length() - 1)


def _scipy(module: str) -> Any:  # noqa: ANN401 - scipy ships no type stubs
    """A scipy module, imported on first use (scipy.stats takes a while to import)."""
    return importlib.import_module(module)


def _sobol(dims: int, points: int, seed: int) -> NDArray[np.float64]:
    qmc = _scipy("scipy.stats.qmc")
    rng = np.random.default_rng(seed)
    try:
        sampler = qmc.Sobol(dims, scramble=True, rng=rng)
    except TypeError:  # pragma: no cover - scipy < 1.15 calls the argument seed
        sampler = qmc.Sobol(dims, scramble=True, seed=rng)
    return np.asarray(sampler.random_base2((points - 1).bit_length()), dtype=np.float64)


def _simplex(start: NDArray[np.float64]) -> NDArray[np.float64]:
    """``start`` and one step along each axis, towards the inside of the cube."""
    vertices = [start.copy()]
    for axis in range(start.size):
        vertex = start.copy()
        step = SIMPLEX_STEP if start[axis] + SIMPLEX_STEP <= 1.0 else -SIMPLEX_STEP
        vertex[axis] = start[axis] + step
        vertices.append(vertex)
    return np.array(vertices)


def _objectives(values: object, count: int) -> list[float]:
    """What ``evaluate`` returned for ``count`` points, as numbers; ``CalibrationError`` if not."""
    try:
        numbers = [float(value) for value in values]  # type: ignore[attr-defined]
    except (TypeError, ValueError, OverflowError):
        numbers = []
    if len(numbers) != count or any(math.isnan(number) for number in numbers):
        msg = f"evaluate returned {show(values)} for {count} points, not {count} numbers"
        raise CalibrationError(msg)
    return numbers


def search(evaluate: BatchObjective, dims: int, *, budget: int, seed: int) -> SearchResult:
    """Minimise ``evaluate`` over ``[0, 1]**dims`` with at most ``budget`` distinct points.

    >>> f = lambda x: list(((x - 0.3) ** 2).sum(axis=1))
    >>> result = search(f, 2, budget=60, seed=0)
    >>> [round(u, 2) for u in result.best], result.evaluations <= 60
    ([0.3, 0.3], True)
    """
    if not callable(evaluate):
        raise CalibrationError(f"evaluate: {show(evaluate)} is not callable")
    dims = check_int("dims", dims, low=1, high=MAX_DIMS, error=CalibrationError)
    budget = check_int("budget", budget, low=1, high=MAX_BUDGET, error=CalibrationError)
    seed = check_int("seed", seed, low=0, high=MAX_SEED, error=CalibrationError)
    steps: list[SearchStep] = []
    seen: dict[tuple[float, ...], float] = {}
    design = design_size(budget)
    points = _sobol(dims, design, seed)[:design]
    values = _objectives(evaluate(points), len(points))
    for point, value in zip(points, values, strict=True):
        unit = tuple(float(u) for u in point)
        seen[unit] = value
        steps.append(SearchStep("design", unit, value))
    best_index = int(np.argmin([step.objective for step in steps]))
    message = "no budget left after the design"

    def scalar(x: NDArray[np.float64]) -> float:
        unit = tuple(float(u) for u in np.clip(x, 0.0, 1.0))
        if unit in seen:
            return seen[unit]
        if len(steps) >= budget:
            raise _BudgetUsed
        (value,) = _objectives(evaluate(np.array([unit])), 1)
        seen[unit] = value
        steps.append(SearchStep("nelder-mead", unit, value))
        return value

    if budget > design:
        start = np.array(steps[best_index].unit)
        try:
            outcome = _scipy("scipy.optimize").minimize(
                scalar,
                start,
                method="Nelder-Mead",
                bounds=[(0.0, 1.0)] * dims,
                options={
                    "initial_simplex": _simplex(start),
                    "xatol": XATOL,
                    "fatol": FATOL,
                    "maxfev": 50 * budget,
                    "maxiter": 50 * budget,
                },
            )
            message = str(outcome.message)
        except _BudgetUsed:
            message = f"evaluation budget of {budget} used"
    best = min(steps, key=lambda step: step.objective)  # first of equals: design order
    return SearchResult(
        best=best.unit,
        objective=best.objective,
        steps=tuple(steps),
        design=design,
        message=message,
    )
