"""The evaluation cache: JSON lines that survive a kill, reuse on a rerun, invalidation by key."""

from __future__ import annotations

import dataclasses
import json

import pytest

from swarmtag.calibration import EvaluationCache, Evaluator, KpiTarget, calibrate
from swarmtag.calibration.cache import CacheEntry
from swarmtag.errors import CalibrationError
from tests.calibration.helpers import tiny_problem, tiny_setup, tiny_targets

POINTS = [{"timing.dock": 0.7}, {"timing.dock": 2.0}, {"timing.dock": 5.0}]


def test_entries_round_trip_through_the_file(tmp_path):
    path = tmp_path / "c.jsonl"
    cache = EvaluationCache(path)
    entry = CacheEntry(values={"tick": 0.1}, achieved={"a": {"pa": 0.25, "throughput": None}})
    cache.put("k1", entry, objective=2.5)
    cache.put("k2", CacheEntry(values={"tick": 0.3}, achieved={"a": {"pa": 1 / 3}}), objective=0.0)
    reopened = EvaluationCache(path)
    assert len(reopened) == 2
    assert reopened.get("k1") == entry
    assert reopened.get("k2").achieved["a"]["pa"] == 1 / 3  # floats exactly
    assert json.loads(path.read_text().splitlines()[0])["objective"] == 2.5


def test_a_line_cut_off_by_a_kill_is_skipped_and_the_next_line_starts_fresh(tmp_path):
    path = tmp_path / "c.jsonl"
    cache = EvaluationCache(path)
    cache.put("k1", CacheEntry(values={"x": 1.0}, achieved={"a": {}}), objective=1.0)
    with path.open("a") as handle:
        handle.write('{"key": "k2", "values": {"x": 2.0}, "achi')
    again = EvaluationCache(path)
    assert (len(again), again.skipped) == (1, 1)
    again.put("k3", CacheEntry(values={"x": 3.0}, achieved={"a": {}}), objective=3.0)
    final = EvaluationCache(path)
    assert ("k1" in final, "k2" in final, "k3" in final, final.skipped) == (True, False, True, 1)


def test_an_unreadable_cache_is_one_line(tmp_path):
    path = tmp_path / "c.jsonl"
    path.write_bytes(b"\xff\xfe\x00")
    with pytest.raises(CalibrationError, match=r"--cache .*: cannot read it"):
        EvaluationCache(path)


def evaluate(problem, cache):
    with Evaluator(problem, cache) as evaluator:
        evaluations = evaluator.evaluate(POINTS)
    return evaluator, evaluations


@pytest.fixture(scope="module")
def first_run(tmp_path_factory):
    path = tmp_path_factory.mktemp("cache") / "c.jsonl"
    evaluator, evaluations = evaluate(tiny_problem(), EvaluationCache(path))
    return path, evaluator, evaluations


def test_a_second_run_evaluates_nothing_new(first_run):
    path, evaluator, evaluations = first_run
    assert (evaluator.computed, evaluator.reused) == (3, 0)
    assert len(path.read_text().splitlines()) == 3
    again, repeated = evaluate(tiny_problem(), EvaluationCache(path))
    assert (again.computed, again.reused) == (0, 3)
    assert [e.objective for e in repeated] == [e.objective for e in evaluations]
    assert [e.achieved for e in repeated] == [e.achieved for e in evaluations]
    assert all(e.cached for e in repeated)
    assert len(path.read_text().splitlines()) == 3  # nothing appended


def test_changed_targets_or_model_invalidate(first_run):
    path, _, _ = first_run
    setup = tiny_setup()
    moved = KpiTarget("p95_latency", value=310.0, low=250.0, high=350.0)
    changed = dataclasses.replace(setup, kpis=(moved, *setup.kpis[1:]))
    for problem in (tiny_problem(targets=tiny_targets(changed)), tiny_problem(model="changed")):
        evaluator, _ = evaluate(problem, EvaluationCache(path))
        assert (evaluator.computed, evaluator.reused) == (3, 0)


def test_an_interrupted_calibration_keeps_its_points_and_resumes(tmp_path):
    path = tmp_path / "c.jsonl"
    problem = tiny_problem()
    seen = []

    def interrupt(evaluation, done, best):
        seen.append(evaluation)
        if done == 2:
            raise KeyboardInterrupt

    options = {"name": "t", "description": "", "base": "base", "command": "swarmtag calibrate"}
    with pytest.raises(KeyboardInterrupt):
        calibrate(
            problem, evaluations=4, cache=EvaluationCache(path), progress=interrupt, **options
        )
    assert len(EvaluationCache(path)) == 2
    result = calibrate(problem, evaluations=4, cache=EvaluationCache(path), **options)
    assert result.reused >= 2
    # The rerun visits the same points first, and finds them in the cache.
    (free,) = problem.free
    resumed = [{free.key: free.from_unit(step.unit[0])} for step in result.search.steps[:2]]
    assert [evaluation.values for evaluation in seen] == resumed
