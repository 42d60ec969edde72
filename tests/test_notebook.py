"""The notebook API (SPEC §8.5): swarmtag.simulate's DataFrames are the CLI's runs and numbers."""

from __future__ import annotations

import importlib
import json
import math
import subprocess
import sys

import numpy as np
import pandas as pd
import pytest

import swarmtag
from swarmtag.analysis import CORE_METRICS, METRICS
from swarmtag.analysis.compare import MIN_RUNS, smallest_mann_whitney_p
from swarmtag.cli import main
from swarmtag.errors import BackendFallback, StatisticsError
from swarmtag.io import read_event_log
from swarmtag.notebook import NotebookResult
from swarmtag.notebook._run import _scenario, _scenario_keys
from swarmtag.policy import Urgency, parse_policy
from swarmtag.sim import load_profile
from swarmtag.sim import simulate as simulate_runs

CONDITIONS = ["proximity", "urgency:alpha=9"]
NAMES = ("proximity", "urgency:alpha=9.0")
SMALL = {"profile": "base", "robots": 3, "carriers": 7, "ticks": 400, "resamples": 200}
"""The fast base world with deliveries within 400 ticks: these tests are about the API."""
RUNS, SEED = 4, 5
SPEC_COLUMNS = ["condition", "run", "seed", "carrier", "urgency0", "order_time", "pickup_time"]
SPEC_COLUMNS += ["delivery_time", "robot"]


@pytest.fixture(scope="module")
def result() -> NotebookResult:
    return swarmtag.simulate(conditions=CONDITIONS, runs=RUNS, seed=SEED, **SMALL)


def same(value, expected) -> bool:
    """Equal, or both undefined (NaN in a DataFrame, None in the report)."""
    if expected is None:
        return math.isnan(value)
    return value == expected


def test_the_top_level_name_is_the_notebook_api():
    from swarmtag import notebook

    assert swarmtag.simulate is notebook.simulate


def test_kpis_are_the_reports_figures(result):
    kpis = result.kpis()
    assert isinstance(kpis, pd.DataFrame)
    assert kpis.index.name == "condition"
    assert list(kpis.index) == list(NAMES)
    assert list(kpis.columns[:4]) == ["runs", "p95_latency", "p95_latency_low", "p95_latency_high"]
    for name in NAMES:
        statistics = result.report.condition(name)
        row = kpis.loc[name]
        assert row["runs"] == RUNS
        assert row["total_deliveries"] == statistics.kpis.total_deliveries > 0
        assert row["undelivered"] == statistics.kpis.undelivered
        for metric in (*METRICS, "pa_at_delivery"):
            estimate = statistics.estimate(metric)
            assert same(row[metric], estimate.value), (name, metric)
            assert same(row[f"{metric}_low"], estimate.confidence_interval.low)
            assert same(row[f"{metric}_high"], estimate.confidence_interval.high)
    assert kpis.loc["proximity", "pa"] == result.report.condition("proximity").pa.value
    assert kpis["runs"].dtype == np.int64


def test_compare_rows_are_the_reports_comparisons(result):
    compared = result.compare()
    assert list(compared.columns) == [
        "condition", "baseline", "metric", "diff", "ci_low", "ci_high", "p_bootstrap",
        "p_mannwhitney", "underpowered", "smallest_p_mannwhitney", "undelivered_differs",
    ]  # fmt: skip
    assert set(compared["baseline"]) == {"proximity"}
    assert list(compared["metric"]) == [*METRICS, "pa_at_delivery"]
    by_metric = {c.metric: c for c in result.report.comparisons}
    pa = compared.set_index("metric").loc["pa"]
    assert pa["condition"] == "urgency:alpha=9.0"
    assert pa["diff"] == by_metric["pa"].diff
    kpis = result.kpis()
    assert pa["diff"] == kpis.loc["urgency:alpha=9.0", "pa"] - kpis.loc["proximity", "pa"]
    assert (pa["ci_low"], pa["ci_high"]) == (
        by_metric["pa"].confidence_interval.low,
        by_metric["pa"].confidence_interval.high,
    )
    assert pa["p_bootstrap"] == by_metric["pa"].p_bootstrap
    assert pa["p_mannwhitney"] == by_metric["pa"].p_mannwhitney
    # 4 runs a side: underpowered, and Mann-Whitney cannot go below 2 / C(8, 4)
    assert RUNS < MIN_RUNS
    assert compared["underpowered"].all()
    assert (compared["smallest_p_mannwhitney"] == smallest_mann_whitney_p(RUNS, RUNS)).all()


def test_compare_with_the_other_baseline_turns_every_difference_round(result):
    forward = result.compare().set_index("metric")
    backward = result.compare(baseline="urgency:alpha=9.0").set_index("metric")
    assert set(backward["condition"]) == {"proximity"}
    assert set(backward["baseline"]) == {"urgency:alpha=9.0"}
    for metric in CORE_METRICS:
        if math.isnan(forward.loc[metric, "diff"]):
            continue
        assert backward.loc[metric, "diff"] == -forward.loc[metric, "diff"]
        assert backward.loc[metric, "ci_low"] == pytest.approx(-forward.loc[metric, "ci_high"])
        assert backward.loc[metric, "p_bootstrap"] == forward.loc[metric, "p_bootstrap"]
        assert backward.loc[metric, "p_mannwhitney"] == pytest.approx(
            forward.loc[metric, "p_mannwhitney"]
        )


@pytest.mark.parametrize("baseline", ["nope", "x" * 5000, np.arange(5000), 3])
def test_a_bad_baseline_is_one_short_line_naming_the_conditions(result, baseline):
    with pytest.raises(ValueError, match=r"proximity, urgency:alpha=9\.0") as refused:
        result.compare(baseline=baseline)
    assert len(str(refused.value)) < 200


def test_a_bad_name_in_the_report_is_refused_in_one_short_line(result):
    # A report (arrays inside) passed by mistake once made a message several KB long.
    with pytest.raises(StatisticsError, match="not a MetricsReport") as refused:
        result.report.condition(result.report)  # type: ignore[arg-type]
    assert len(str(refused.value)) < 200
    with pytest.raises(StatisticsError, match="no condition 'nope'; this report has proximity"):
        result.report.condition("nope")


def test_events_are_the_event_log(result):
    events = result.events
    assert list(events.columns[: len(SPEC_COLUMNS)]) == SPEC_COLUMNS
    assert len(events) == len(result.log) == len(NAMES) * RUNS * 7
    assert (events["time_unit"] == "tick").all()
    undelivered = events["delivery_time"].isna()
    assert undelivered.sum() == result.kpis()["undelivered"].sum()
    assert events.loc[undelivered, "robot"].isna().all()
    assert events.loc[~undelivered, "robot"].notna().all()
    np.testing.assert_array_equal(events["order_time"].to_numpy(), result.log.order_time)
    assert set(result.event_table["kind"]) >= {"select"}
    events.loc[0, "carrier"] = 99  # a new frame each time: the log stays as it was
    assert result.events.loc[0, "carrier"] == result.log.carrier[0]


def test_runs_and_numbers_are_the_command_lines(result, tmp_path, capsys):
    path = tmp_path / "events.csv"
    argv = ["simulate", "--profile", "base", "--robots", "3", "--carriers", "7", "--ticks", "400"]
    argv += ["--resamples", "200", "--runs", str(RUNS), "--seed", str(SEED), "--no-progress"]
    argv += [*(f"--condition={name}" for name in CONDITIONS), "--events", str(path), "--json"]
    with pytest.raises(SystemExit) as exited:
        main(argv)
    out, _ = capsys.readouterr()
    assert exited.value.code in (0, None)
    assert read_event_log(path).sorted() == result.log.sorted()
    document = json.loads(out)
    kpis = result.kpis()
    for entry in document["conditions"]:
        row = kpis.loc[entry["condition"]]
        assert (row["runs"], row["total_deliveries"]) == (entry["runs"], entry["total_deliveries"])
        for metric in CORE_METRICS:
            assert same(row[metric], entry[metric]["value"]), metric
            assert same(row[f"{metric}_low"], entry[metric]["ci"][0])
    compared = result.compare().set_index("metric")
    for entry in document["comparisons"]:
        assert same(compared.loc[entry["metric"], "diff"], entry["diff"])
        assert same(compared.loc[entry["metric"], "p_bootstrap"], entry["p_bootstrap"])
        assert compared.loc[entry["metric"], "underpowered"] == entry["underpowered"]


def test_each_conditions_runs_are_the_simulators(result):
    scenario = load_profile("base").scenario({"robots": 3, "carriers": 7, "ticks": 400})
    assert result.scenario == scenario
    for name in CONDITIONS:
        alone = simulate_runs(scenario, parse_policy(name), seed=SEED, runs=RUNS).carriers
        assert result.log.take(result.log.condition == alone.condition[0]) == alone
    later = simulate_runs(scenario, parse_policy("proximity"), seed=SEED, runs=1, run_offset=3)
    assert result.log.take((result.log.condition == "proximity") & (result.log.run == 3)) == (
        later.carriers
    )


def test_the_same_seed_gives_the_same_frames_and_another_seed_others(result):
    again = swarmtag.simulate(conditions=CONDITIONS, runs=RUNS, seed=SEED, **SMALL)
    pd.testing.assert_frame_equal(again.kpis(), result.kpis())
    pd.testing.assert_frame_equal(again.compare(), result.compare())
    pd.testing.assert_frame_equal(again.events, result.events)
    other = swarmtag.simulate(conditions=CONDITIONS, runs=RUNS, seed=SEED + 1, **SMALL)
    assert not other.events.equals(result.events)


def test_conditions_keep_their_order_and_take_policy_objects():
    chosen = swarmtag.simulate(conditions=[Urgency(alpha=9), "proximity"], runs=2, seed=1, **SMALL)
    assert chosen.conditions == ("urgency:alpha=9.0", "proximity")
    assert list(chosen.kpis().index) == ["urgency:alpha=9.0", "proximity"]
    assert chosen.report.baseline == "proximity"
    assert set(chosen.compare()["condition"]) == {"urgency:alpha=9.0"}
    assert "runs=2" in repr(chosen)


def test_policy_files_add_their_rules(tmp_path):
    # a name of its own: a process holds one rule per condition name, and other tests in
    # the same worker load the examples' urgency_first from elsewhere
    path = tmp_path / "notebook_rules.py"
    path.write_text(
        "def notebook_urgency(urgency, distance, **context):\n"
        "    return urgency - 0.1 * distance\n",
        encoding="utf-8",
    )
    given = {**SMALL, "ticks": 100}
    with pytest.warns(BackendFallback, match="notebook_urgency"):  # Python: reference backend
        chosen = swarmtag.simulate(
            conditions="proximity", policy_files=f"{path}:notebook_urgency", runs=1, **given
        )
    assert chosen.conditions == ("proximity", "notebook_urgency")
    assert chosen.kpis().loc["notebook_urgency", "runs"] == 1


def test_overrides_are_scenario_keys_parts_or_the_commands_flags():
    profile = load_profile("base")
    assert _scenario_keys(
        {"robots": 4, "camera__range": 2.0, "urgency_model": "static", "camera": {"memory": 3.0}}
    ) == {"robots": 4, "camera.range": 2.0, "urgency.model": "static", "camera": {"memory": 3.0}}
    _, scenario = _scenario(profile, {"radio_range": 2.5, "ticks": 90})
    assert (scenario.radio.range, scenario.ticks) == (2.5, 90)


def test_plots_draw_one_line_per_condition(result):
    import matplotlib as mpl

    mpl.use("Agg")
    import matplotlib.pyplot as plt

    figure, axes = plt.subplots(1, 2)
    try:
        assert result.plot_pa(ax=axes[0]) is axes[0]
        assert len(axes[0].get_lines()) == len(NAMES)
        assert [t.get_text() for t in axes[0].get_legend().get_texts()] == list(NAMES)
        assert result.plot_latency(ax=axes[1]) is axes[1]
        assert axes[1].get_xlabel() == "percentile of pooled latencies"
    finally:
        plt.close(figure)
    drawn = result.plot_latency()
    try:
        assert len(drawn.get_lines()) == len(NAMES)
    finally:
        plt.close(drawn.figure)


@pytest.mark.parametrize(
    ("arguments", "match"),
    [
        ({"conditions": ["nope"]}, "unknown policy 'nope'"),
        ({"conditions": ["x" * 5000]}, r"conditions\[0\]: 'x.*5000 characters"),
        ({"conditions": [np.arange(5000)]}, r"conditions\[0\]: a ndarray is not a condition name"),
        ({"conditions": 3}, "conditions: a int is not a name or a list"),
        ({"conditions": []}, "name at least one condition"),
        ({"conditions": ["proximity", "Proximity"]}, "condition given twice: proximity"),
        ({"policy_files": [np.arange(9)]}, r"policy_files\[0\]: a ndarray is not FILE.py"),
        ({"baseline": "edf"}, "baseline 'edf' is not one of the conditions: proximity, urgency"),
        ({"robotz": 3}, "robotz: unknown key; a scenario has keys"),
        ({"robots": "x"}, "robots: 'x' is not an integer"),
        ({"robots": np.arange(5000)}, "robots: array"),
        ({"camera": list(range(5000))}, r"camera: \[0, 1, .* \.\.\. .*is not a table of keys"),
        ({"camera_range": 2.0, "camera__range": 3.0}, "camera_range and camera__range both set"),
        ({"profile": np.arange(9)}, "profile: a ndarray is not a profile name"),
        ({"profile": "nope"}, "profile 'nope': no such shipped profile"),
        ({"runs": 0}, "runs: 0 is not an integer"),
        ({"seed": np.arange(5000)}, "seed: array"),
        ({"resamples": 0}, "resamples: 0 is not an integer"),
        ({"backend": "gpu"}, "gpu"),
        ({"controller": "nope"}, "nope"),
    ],
)
def test_bad_input_is_one_short_value_error_before_any_run(arguments, match):
    given = {"conditions": CONDITIONS, "runs": 2, **SMALL, **arguments}
    with pytest.raises(ValueError, match=match) as refused:
        swarmtag.simulate(**given)
    assert len(str(refused.value)) <= 500


def test_without_pandas_the_extra_is_named(monkeypatch):
    monkeypatch.setitem(sys.modules, "pandas", None)
    with pytest.raises(ImportError, match=r"pip install 'swarmtag\[pandas\]'"):
        swarmtag.simulate(conditions=CONDITIONS, runs=1, **SMALL)
    monkeypatch.delitem(sys.modules, "swarmtag.notebook._frames", raising=False)
    with pytest.raises(ImportError, match=r"pip install 'swarmtag\[pandas\]'"):
        importlib.import_module("swarmtag.notebook._frames")


def test_importing_the_api_imports_neither_pandas_nor_matplotlib():
    script = (
        "import sys, swarmtag; swarmtag.simulate; "
        "print(sorted({'pandas', 'matplotlib'} & set(sys.modules)))"
    )
    done = subprocess.run(
        [sys.executable, "-c", script], capture_output=True, text=True, check=True, timeout=60
    )
    assert done.stdout.strip() == "[]"
