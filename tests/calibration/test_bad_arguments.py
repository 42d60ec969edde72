"""The public calibration functions refuse nonsense with ``CalibrationError`` (issue 35, item 7)."""

from __future__ import annotations

import math
from pathlib import Path

import pytest

from swarmtag.calibration import (
    KpiTarget,
    check_evaluations,
    default_cache_path,
    half_width,
    load_baseline,
    objective,
    parse_free,
    parse_free_list,
    read_target_file,
    residual,
    search,
    target_path,
)
from swarmtag.errors import CalibrationError

TARGET = KpiTarget("pa", value=0.3, low=0.2, high=0.4)


def _flat(points):
    return [0.0 for _ in points]


@pytest.mark.parametrize(
    "call",
    [
        lambda: check_evaluations(1.5),
        lambda: check_evaluations("3"),
        lambda: check_evaluations(None),
        lambda: default_cache_path(3),
        lambda: default_cache_path(Path("/")),
        lambda: half_width(0.3, 0.1),
        lambda: half_width(TARGET, math.nan),
        lambda: residual(TARGET, "x"),
        lambda: residual(None, 0.1),
        lambda: load_baseline(3),
        lambda: load_baseline("a\0.csv"),
        lambda: read_target_file(None),
        lambda: objective(3),
        lambda: objective([1.0]),
        lambda: parse_free(3),
        lambda: parse_free_list("tick=0.05:0.2"),
        lambda: target_path(["lab"]),
        lambda: search(_flat, 0, budget=3, seed=0),
        lambda: search(_flat, 2, budget=math.inf, seed=0),
        lambda: search(_flat, 2, budget=10**30, seed=0),
        lambda: search(_flat, 2, budget=3, seed=-1),
        lambda: search(lambda points: [None] * len(points), 2, budget=3, seed=0),
        lambda: search(lambda points: [math.nan] * len(points), 2, budget=3, seed=0),
        lambda: search(3, 2, budget=3, seed=0),
    ],
)
def test_wrong_kinds_and_values_are_calibration_errors(call):
    with pytest.raises(CalibrationError):
        call()


def test_valid_calls_still_answer():
    assert residual(TARGET, None) is None
    assert residual(TARGET, 10**5000) is None  # beyond float range: undefined, as inf is
    assert check_evaluations(5) == 5
    assert default_cache_path(Path("out/lab.toml")) == Path("out/lab.cache.jsonl")
