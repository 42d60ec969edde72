"""Running a calibration: search, round, re-evaluate at the rounded point, build the profile.

``calibrate`` ties the pieces together: the search (``search.py``) proposes
points in the unit cube, the evaluator (``evaluate.py``) simulates them
through the cache, and the best point is rounded to ``SIGNIFICANT_DIGITS``
significant digits (kept within the bounds) and evaluated again: the
rounded point is what the profile holds, so its objective is what is
reported. The fitted profile is the base profile with ``--set`` and the
fitted values substituted, and a ``[profile.calibration]`` record of how it
was made.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any, Final

import numpy as np
from numpy.typing import NDArray

from swarmtag import __version__
from swarmtag._checks import MAX_WORKERS, check_instance, check_int, check_text, show
from swarmtag.calibration.cache import EvaluationCache
from swarmtag.calibration.evaluate import Evaluation, Evaluator
from swarmtag.calibration.problem import CalibrationProblem
from swarmtag.calibration.search import SearchResult, search
from swarmtag.errors import CalibrationError
from swarmtag.sim.config.profiles import Profile

__all__ = [
    "DEFAULT_EVALUATIONS",
    "MAX_EVALUATIONS",
    "SIGNIFICANT_DIGITS",
    "CalibrationResult",
    "calibrate",
    "check_evaluations",
]

SIGNIFICANT_DIGITS: Final = 4
"""Fitted values are written with this many significant digits."""
DEFAULT_EVALUATIONS: Final = 32
"""Evaluations when neither ``--evaluations`` nor the target file names a number."""
MAX_EVALUATIONS: Final = 5_000
"""Most evaluations of one calibration."""

Progress = Callable[[Evaluation, int, float], None]
"""Called after each evaluation with it, the evaluations so far and the best objective so far."""


def check_evaluations(evaluations: int) -> int:
    """``evaluations`` if it is an integer in 1..``MAX_EVALUATIONS``, else ``CalibrationError``.

    >>> check_evaluations(0)
    Traceback (most recent call last):
    ...
    swarmtag.errors.CalibrationError: --evaluations: 0 is not an integer in 1-5000
    """
    return check_int(
        "--evaluations", evaluations, low=1, high=MAX_EVALUATIONS, error=CalibrationError
    )


@dataclass(frozen=True)
class CalibrationResult:
    """A finished calibration: the search, the fitted (rounded) values and their evaluation."""

    problem: CalibrationProblem
    search: SearchResult
    best: Mapping[str, float]
    """The best point of the search, unrounded."""
    fitted: Mapping[str, float]
    """The rounded values the profile holds."""
    evaluation: Evaluation
    """The evaluation at ``fitted``: its objective is the reported one."""
    profile: Profile
    computed: int
    """Points simulated in this call (the rest came from the cache)."""
    reused: int
    """Points taken from the cache."""

    @property
    def objective(self) -> float:
        """The objective at the rounded point."""
        return self.evaluation.objective


def _values(problem: CalibrationProblem, unit: NDArray[np.float64]) -> dict[str, float]:
    return {p.key: p.from_unit(float(u)) for p, u in zip(problem.free, unit, strict=True)}


def _record(
    problem: CalibrationProblem,
    result: SearchResult,
    fitted: Mapping[str, float],
    objective: float,
    *,
    budget: int,
    base: str,
    command: str,
) -> dict[str, Any]:
    targets = problem.targets
    record: dict[str, Any] = {
        "baseline": targets.source,
        "baseline_kind": targets.kind,
        "baseline_sha256": targets.source_digest,
        "condition": targets.condition,
        "base_profile": base,
        "free": [parameter.spec for parameter in problem.free],
    }
    if problem.settings:
        record["settings"] = dict(problem.settings)
    record.update(
        {
            "fitted": dict(fitted),
            "objective": objective,
            "search_objective": result.objective,
            "significant_digits": SIGNIFICANT_DIGITS,
            "evaluations": budget,
            "evaluations_done": result.evaluations,
            "seed": problem.seed,
            "runs": {setup.name: problem.simulated_runs(setup) for setup in targets.setups},
            "model": problem.model,
            "swarmtag": __version__,
            "command": command,
        }
    )
    return record


def calibrate(
    problem: CalibrationProblem,
    *,
    evaluations: int,
    cache: EvaluationCache,
    name: str,
    description: str,
    base: str,
    command: str,
    workers: int = 1,
    progress: Progress | None = None,
) -> CalibrationResult:
    """Fit ``problem`` with at most ``evaluations`` search points; the profile and its fit.

    ``name`` and ``description`` go into the profile, ``base`` (the base
    profile as named) and ``command`` (the command line that re-creates it)
    into its calibration record. ``progress`` is told of every evaluation.
    """
    check_instance("problem", problem, CalibrationProblem, error=CalibrationError)
    check_instance("cache", cache, EvaluationCache, error=CalibrationError)
    for label, text in (("name", name), ("description", description), ("base", base)):
        check_text(label, text, error=CalibrationError)
    check_text("command", command, error=CalibrationError)
    check_int("workers", workers, low=1, high=MAX_WORKERS, error=CalibrationError)
    if progress is not None and not callable(progress):
        raise CalibrationError(f"progress: {show(progress)} is not callable")
    budget = check_evaluations(evaluations)
    best_so_far = [float("inf")]
    done = [0]

    def tell(evaluation: Evaluation) -> None:
        done[0] += 1
        best_so_far[0] = min(best_so_far[0], evaluation.objective)
        if progress is not None:
            progress(evaluation, done[0], best_so_far[0])

    with Evaluator(problem, cache, workers=workers, on_result=tell) as evaluator:

        def batch(points: NDArray[np.float64]) -> list[float]:
            evaluated = evaluator.evaluate([_values(problem, point) for point in points])
            return [evaluation.objective for evaluation in evaluated]

        result = search(batch, len(problem.free), budget=budget, seed=problem.seed)
        best = _values(problem, np.array(result.best))
        fitted = {p.key: p.clamp_round(best[p.key], SIGNIFICANT_DIGITS) for p in problem.free}
        (evaluation,) = evaluator.evaluate([fitted])
        computed, reused = evaluator.computed, evaluator.reused
    record = _record(
        problem,
        result,
        fitted,
        evaluation.objective,
        budget=budget,
        base=base,
        command=command,
    )
    profile = Profile(
        name=name,
        description=description,
        values=problem.profile_values(fitted),
        calibration=record,
    )
    return CalibrationResult(
        problem=problem,
        search=result,
        best=best,
        fitted=fitted,
        evaluation=evaluation,
        profile=profile,
        computed=computed,
        reused=reused,
    )
