"""The search on cheap deterministic objectives: minimum found within bounds, budget kept."""

from __future__ import annotations

import numpy as np
import pytest

from swarmtag.calibration import search
from swarmtag.calibration.search import design_size
from swarmtag.errors import CalibrationError


class Counting:
    """A batch objective that records every point it is asked for."""

    def __init__(self, function):
        self.function = function
        self.points: list[tuple[float, ...]] = []
        self.batches: list[int] = []

    def __call__(self, points):
        self.batches.append(len(points))
        self.points += [tuple(point) for point in points]
        return [float(self.function(np.asarray(point))) for point in points]


def quadratic(centre):
    return lambda x: float(np.sum((x - np.asarray(centre)) ** 2))


@pytest.mark.parametrize("centre", [(0.3,), (0.71, 0.22), (0.6, 0.4, 0.15)])
def test_finds_the_minimum_of_a_quadratic(centre):
    objective = Counting(quadratic(centre))
    result = search(objective, len(centre), budget=80, seed=0)
    assert np.allclose(result.best, centre, atol=0.01)
    assert result.objective == min(step.objective for step in result.steps)
    assert all(0.0 <= u <= 1.0 for point in objective.points for u in point)


def test_a_minimum_outside_the_bounds_ends_on_the_bound():
    objective = Counting(quadratic((1.4, 0.5)))
    result = search(objective, 2, budget=60, seed=1)
    assert result.best[0] == pytest.approx(1.0, abs=1e-3)
    assert result.best[1] == pytest.approx(0.5, abs=0.02)
    assert all(0.0 <= u <= 1.0 for point in objective.points for u in point)


@pytest.mark.parametrize("budget", [1, 2, 5, 13, 40])
def test_the_budget_counts_distinct_points_and_the_design_comes_first(budget):
    objective = Counting(quadratic((0.5, 0.5)))
    result = search(objective, 2, budget=budget, seed=0)
    assert result.evaluations == len(objective.points) <= budget
    assert len(set(objective.points)) == len(objective.points)  # no point asked for twice
    assert result.design == design_size(budget)
    assert objective.batches[0] == result.design  # the design is one parallel batch
    assert [step.phase for step in result.steps[: result.design]] == ["design"] * result.design
    assert {step.phase for step in result.steps[result.design :]} <= {"nelder-mead"}


def test_a_rough_objective_uses_the_whole_budget():
    rough = Counting(lambda x: float(np.floor(40 * abs(x[0] - 0.37))) + 0.01 * x[1])
    result = search(rough, 2, budget=24, seed=0)
    assert result.evaluations == 24
    assert "budget of 24 used" in result.message


def test_deterministic_in_the_seed():
    first = search(Counting(quadratic((0.2, 0.8))), 2, budget=30, seed=5)
    again = search(Counting(quadratic((0.2, 0.8))), 2, budget=30, seed=5)
    other = search(Counting(quadratic((0.2, 0.8))), 2, budget=30, seed=6)
    assert first == again
    assert first.steps[0].unit != other.steps[0].unit


def test_design_sizes():
    assert [design_size(n) for n in (1, 2, 3, 4, 7, 8, 64, 65)] == [1, 1, 1, 2, 2, 4, 32, 32]


def test_refuses_an_empty_search():
    with pytest.raises(CalibrationError, match=r"budget: 0 is not an integer in 1-100000"):
        search(Counting(quadratic((0.5,))), 1, budget=0, seed=0)
