"""Warehouse studies: summaries over the orders placed after the warm-up, raw logs kept whole."""

from __future__ import annotations

import importlib
import json
from typing import Any

import numpy as np
import pytest

from swarmtag.analysis import summarize, trim_warmup
from swarmtag.analysis.tables import markdown_tables
from swarmtag.cli import main
from swarmtag.data import example_trial_path
from swarmtag.errors import StudyError
from swarmtag.experiments import (
    REPRODUCED,
    STUDIES,
    ResultsStore,
    Study,
    kpi_log,
    load_study,
    run_study,
    study_key,
)
from swarmtag.experiments.report import write_report
from swarmtag.io import read_event_log

from .helpers import small_study

TINY: dict[str, Any] = {
    "name": "tiny-warehouse",
    "conditions": ["proximity", "urgency:alpha=3.0"],
    "runs": 2,
    "quick_runs": 1,
    "ticks": 600,
    "chunk_runs": 2,
    "resamples": 50,
    "profile": "base",  # ticks, and the quick base world: the machinery is under test
    "backend": "reference",
    "scenario": {
        "robots": 3,
        "warehouse": {"map": "small-warehouse", "order_interval": 3.0, "warmup": 20.0},
    },
}
"""Two 60 s runs per condition; the window starts at 20 s, tick 200."""


@pytest.fixture(scope="module")
def tiny(tmp_path_factory):
    out = tmp_path_factory.mktemp("warehouse") / "out"
    study = Study.from_mapping(TINY)
    result = run_study(study, out_dir=out, workers=1)
    with ResultsStore(out / "results.duckdb", read_only=True) as store:
        log = store.load_log(study_key(study, "default"), study.conditions, 2)
    return study, result, out, log


def test_summaries_cover_the_orders_placed_after_the_warmup(tiny):
    study, result, _, log = tiny
    assert log.time_unit == "tick"
    assert (log.order_time < 200).any()  # the store keeps every order
    window = trim_warmup(log, 200.0)
    assert kpi_log(log, study.scales[0]) == window
    expected = summarize(window, baseline="proximity", n_resamples=50, seed=0).to_json()
    assert result.metrics["default"] == json.loads(json.dumps(expected))
    assert json.loads(result.metrics_paths["default"].read_text()) == result.metrics["default"]
    whole = summarize(log, baseline="proximity", n_resamples=50, seed=0).to_json()
    assert whole != expected
    carriers = [c["total_deliveries"] + c["undelivered"] for c in expected["conditions"]]
    assert carriers == [int((window.condition == c).sum()) for c in study.conditions]


def test_the_report_tables_use_the_window_and_the_exports_every_order(tiny):
    study, result, out, log = tiny
    write_report(out, [study], computed=[result])
    folder = out / study.name / "default"
    window = summarize(trim_warmup(log, 200.0), baseline="proximity", n_resamples=50, seed=0)
    assert (folder / "tables.md").read_text().startswith(markdown_tables(window))
    assert read_event_log(folder / "carriers.csv") == log
    html = (out / "report.html").read_text(encoding="utf-8")
    assert "KPI window" in html
    assert "orders placed at or after 20 s" in html
    assert "warehouse small-warehouse" in html


def test_kpi_warmup_is_the_first_tick_of_the_window():
    (scale,) = Study.from_mapping(TINY).scales
    assert (scale.kpi_warmup("tick"), scale.kpi_warmup("s")) == (200.0, 200 * 0.1)
    odd = {**TINY["scenario"], "warehouse": {"map": "small-warehouse", "warmup": 0.25}}
    (scale,) = Study.from_mapping({**TINY, "scenario": odd}).scales
    assert (scale.kpi_warmup("tick"), scale.kpi_warmup("s")) == (3.0, 3 * 0.1)
    (plain,) = small_study().scales
    assert plain.kpi_warmup("tick") == 0.0
    log = read_event_log(example_trial_path())
    assert kpi_log(log, plain) is log


def test_the_shipped_warehouse_study():
    study = load_study("warehouse")
    assert STUDIES["warehouse"] == "warehouse.toml"
    assert "warehouse" not in REPRODUCED
    assert list(study.conditions) == ["proximity", "urgency:alpha=0.7", "urgency:alpha=3.0"]
    assert (study.baseline, study.profile, study.backend, study.urgency) == (
        "proximity", "lab", None, "growing",
    )  # fmt: skip
    assert (study.runs, study.quick_runs) == (20, 4)
    shapes = [
        (s.key, s.scenario.robots, s.scenario.run_ticks, s.scenario.time_unit) for s in study.scales
    ]
    assert shapes == [("small", 6, 36000, "s"), ("hall", 36, 36000, "s")]
    warehouses = [s.scenario.warehouse for s in study.scales]
    assert [(w.map, w.order_interval, w.warmup) for w in warehouses if w is not None] == [
        ("small-warehouse", 45.0, 600.0),
        ("warehouse-hall", 20.0, 600.0),
    ]
    assert [s.kpi_warmup("s") for s in study.scales] == [6000 * 0.1] * 2


def test_reproduce_runs_only_the_spec_studies_by_default(tmp_path, capsys, monkeypatch):
    loaded: list[str] = []

    def load(name):
        loaded.append(name)
        return small_study()

    def stop(*args, **kwargs):
        raise StudyError("stopped")

    monkeypatch.setattr("swarmtag.experiments.load_study", load)
    # the package's reproduce() shadows its module's name: patch the module itself
    monkeypatch.setattr(
        importlib.import_module("swarmtag.experiments.reproduce"), "run_study", stop
    )
    with pytest.raises(SystemExit) as exited:
        main(["reproduce", "--quick", "--out", str(tmp_path / "out"), "--workers", "1"])
    assert exited.value.code == 2
    assert "stopped" in capsys.readouterr().err
    assert loaded == list(REPRODUCED)
    assert np.isin(list(REPRODUCED), list(STUDIES)).all()


def test_a_warmup_that_empties_a_run_names_the_scale(tiny):
    study, _, _, log = tiny
    early = log.take(log.order_time < 200)
    with pytest.raises(
        StudyError, match=r"^scales\.default: warehouse\.warmup: warm-up 200: run 0 "
    ):
        kpi_log(early, study.scales[0])
