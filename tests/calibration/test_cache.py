"""The evaluation cache: JSON lines that survive a kill, reuse on a rerun, invalidation by key."""

from __future__ import annotations

import dataclasses
import json
import math
import time

import pytest

from swarmtag.calibration import EvaluationCache, Evaluator, KpiTarget, calibrate
from swarmtag.calibration.cache import CacheEntry, parse_line
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


# --- a corrupted cache is never used (issue 35) --------------------------------------------


def _set_latency(value):
    def change(record):
        record["achieved"]["tiny"]["p95_latency"] = value

    return change


def _rename(table, old, new):
    def change(record):
        where = record if table is None else record[table]
        where[new] = where.pop(old)

    return change


def _double_latency(record):
    record["achieved"]["tiny"]["p95_latency"] *= 2


def _drop_check(record):
    del record["check"]


DEEP = "[" * 2000 + "1" + "]" * 2000
CORRUPTIONS = {
    "NaN": (_set_latency(math.nan), None),
    "Infinity": (_set_latency(math.inf), None),
    "-Infinity": (_set_latency(-math.inf), None),
    "null": (_set_latency(None), None),
    "400-digit integer": (_set_latency(int("9" * 400)), None),
    "400-digit float": (_set_latency(0.5), ("0.5", "0." + "5" * 400)),
    "-1e308": (_set_latency(-1e308), None),
    "deep nesting": (_set_latency("deep"), ('"deep"', DEEP)),
    "renamed key": (_rename(None, "achieved", "achieve"), None),
    "renamed KPI": (_rename("achieved", "tiny", "other"), None),
    "edited number": (_double_latency, None),
    "line without a check": (_drop_check, None),
    "key given twice": (lambda record: None, ('{"achieved"', '{"objective": 0, "achieved"')),
    "not an object": (lambda record: record.clear(), ("{}", "[1, 2]")),
}
"""What a corrupted line holds: a change to its record, then one to its text."""


@pytest.mark.parametrize("corruption", CORRUPTIONS)
def test_a_corrupted_line_is_simulated_again_and_the_fit_is_unchanged(
    first_run, tmp_path, corruption
):
    path, _, clean = first_run
    lines = path.read_text().splitlines()[:3]  # its own points (other tests append theirs)
    change, (old, new) = CORRUPTIONS[corruption][0], CORRUPTIONS[corruption][1] or ("", "")
    record = json.loads(lines[1])
    change(record)
    lines[1] = json.dumps(record, sort_keys=True).replace(old, new, 1)
    corrupted = tmp_path / "c.jsonl"
    corrupted.write_text("\n".join(lines) + "\n")
    cache = EvaluationCache(corrupted)
    evaluator, evaluations = evaluate(tiny_problem(), cache)
    assert [e.objective for e in evaluations] == [e.objective for e in clean]
    assert [e.achieved for e in evaluations] == [e.achieved for e in clean]
    assert (evaluator.computed, evaluator.reused) == (1, 2)
    assert [number for number, _ in cache.skipped_lines] == [2]
    assert cache.skipped_note().startswith(f"1 line of {corrupted} could not be used (line 2; ")


@pytest.mark.parametrize(
    ("line", "why"),
    [
        ('{"a": NaN}', "NaN is not a number JSON allows"),
        ('{"a": ' + "9" * 400 + "}", "an integer of 400 digits"),
        (DEEP, "nested more than 4 levels deep"),
        ('{"a": 1, "a": 2}', "a key given twice"),
        ("[1, 2]", "the line: not an object"),
        ('{"key": "k"}', "keys achieved, check, objective, values missing"),
    ],
)
def test_each_bad_line_says_why(line, why):
    with pytest.raises(CalibrationError) as refused:
        parse_line(line)
    assert str(refused.value) == why


def test_a_hostile_line_is_refused_in_linear_time():
    started = time.perf_counter()
    for line in ('"' + '\\"' * 200_000, "[" * 500_000, '"' * 400_000):
        with pytest.raises(CalibrationError):
            parse_line(line)
    assert time.perf_counter() - started < 5


def test_the_note_names_every_skipped_line_in_one_line(tmp_path, monkeypatch):
    path = tmp_path / "c.jsonl"
    cache = EvaluationCache(path)
    for index in range(3):
        entry = CacheEntry(values={"x": float(index)}, achieved={"a": {"pa": 0.5}})
        cache.put(f"k{index}", entry, objective=1.0)
    lines = path.read_text().splitlines()
    monkeypatch.setattr("swarmtag.calibration.cache.MAX_LINE_BYTES", 500)
    long = '{"key": "' + "x" * 2000 + '"}'
    path.write_text("\n".join([lines[0], "oops", "NaN", lines[1], long, lines[2], "{"]) + "\n")
    reopened = EvaluationCache(path)
    assert (len(reopened), reopened.skipped) == (3, 4)
    note = reopened.skipped_note()
    assert note == (
        f"4 lines of {path} could not be used (lines 2-3, 5, 7; line 2: not JSON "
        "(Expecting value: line 1 column 1 (char 0))); a point found in no other line is "
        "simulated again"
    )
    assert "\n" not in note
