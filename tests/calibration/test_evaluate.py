"""Evaluations: common random numbers, and results independent of chunks and worker processes."""

from __future__ import annotations

import pytest

from swarmtag.analysis import ConditionRuns, condition_kpis, run_values
from swarmtag.calibration import EvaluationCache, Evaluator
from swarmtag.calibration import evaluate as evaluate_module
from swarmtag.calibration.evaluate import chunk_runs
from swarmtag.policy import parse_policy
from swarmtag.sim import simulate
from tests.calibration.helpers import tiny_problem, tiny_setup, tiny_targets

POINTS = [{"timing.dock": 0.8}, {"timing.dock": 4.0}]


def evaluate(problem, *, workers=1):
    with Evaluator(problem, EvaluationCache(None), workers=workers) as evaluator:
        return evaluator.evaluate(POINTS)


@pytest.fixture(scope="module")
def problem():
    return tiny_problem(targets=tiny_targets(tiny_setup(runs=4)))


@pytest.fixture(scope="module")
def reference(problem):
    return evaluate(problem)


def test_an_evaluation_is_the_kpis_of_the_same_runs_at_the_point(problem, reference):
    setup = problem.targets.setups[0]
    for values, evaluation in zip(POINTS, reference, strict=True):
        scenario = problem.scenario(setup, values)
        log = simulate(scenario, parse_policy("proximity"), seed=0, runs=4).carriers
        kpis = condition_kpis(run_values(ConditionRuns.from_log(log, "proximity")))
        assert evaluation.achieved[setup.name] == {
            "p95_latency": kpis.p95_latency,
            "deliveries_per_run": kpis.deliveries_per_run,
        }
        assert not evaluation.cached
    assert reference[0].achieved != reference[1].achieved  # the point matters


def test_chunks_do_not_change_the_result(problem, reference, monkeypatch):
    monkeypatch.setattr(evaluate_module, "chunk_runs", lambda runs, workers: 1)
    assert [e.achieved for e in evaluate(problem)] == [e.achieved for e in reference]


def test_worker_processes_give_the_same_result(problem, reference):
    assert chunk_runs(4, 2) == 2  # two chunks per point: four jobs in the pool
    pooled = evaluate(problem, workers=2)
    assert [e.achieved for e in pooled] == [e.achieved for e in reference]
    assert [e.objective for e in pooled] == [e.objective for e in reference]


def test_a_point_given_twice_is_simulated_once(problem):
    with Evaluator(problem, EvaluationCache(None)) as evaluator:
        first, second = evaluator.evaluate([POINTS[0], dict(POINTS[0])])
    assert evaluator.computed == 1
    assert first == second
