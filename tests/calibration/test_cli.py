"""``swarmtag calibrate`` end to end: a small profile re-derived, reread, reproduced byte for byte."""

from __future__ import annotations

import math
import shutil

import pytest

from swarmtag.calibration import load_baseline
from swarmtag.calibration.objective import achieved_kpis, fit_rows, objective
from swarmtag.cli import calibrate as calibrate_cli
from swarmtag.cli import main
from swarmtag.data import example_trial_path
from swarmtag.policy import parse_policy
from swarmtag.sim import simulate
from swarmtag.sim.config.profiles import read_profile_file
from tests.calibration.helpers import SMALL_TARGETS


def run(argv, capsys):
    with pytest.raises(SystemExit) as exit_info:
        main(["calibrate", *argv])
    out, err = capsys.readouterr()
    return exit_info.value.code, out, err


@pytest.fixture(scope="module")
def calibrated(tmp_path_factory):
    """Calibrate the small target file twice with the same command; keep both outputs."""
    folder = tmp_path_factory.mktemp("calibrate")
    shutil.copy(SMALL_TARGETS, folder / "small.toml")
    argv = [
        "--baseline",
        str(folder / "small.toml"),
        "--profile",
        "base",
        "--out",
        str(folder / "small.profile.toml"),
        "--report",
        str(folder / "fit.md"),
        "--workers",
        "1",
        "--no-progress",
    ]
    results = []
    for _ in range(2):
        with pytest.raises(SystemExit) as exit_info:
            main(["calibrate", *argv])
        assert exit_info.value.code == 0
        results.append(
            {
                "profile": (folder / "small.profile.toml").read_bytes(),
                "report": (folder / "fit.md").read_text(encoding="utf-8"),
                "cache": (folder / "small.profile.cache.jsonl").read_text().splitlines(),
            }
        )
    return folder, results


def test_the_profile_reads_back_with_its_record(calibrated):
    folder, _ = calibrated
    profile = read_profile_file(folder / "small.profile.toml")
    record = profile.calibration
    assert profile.name == "small"
    assert profile.description == "A small test calibration"
    assert record["baseline"] == str(folder / "small.toml")
    assert record["baseline_kind"] == "targets"
    assert record["free"] == ["timing.dock=0.5:8.0:log"]
    assert (record["evaluations"], record["seed"], record["runs"]) == (5, 0, {"3x7-short": 6})
    assert record["evaluations_done"] <= 5
    assert record["significant_digits"] == 4
    dock = record["fitted"]["timing.dock"]
    assert 0.5 <= dock <= 8.0
    assert float(f"{dock:.4g}") == dock
    assert profile.values["timing"]["dock"] == dock
    assert record["command"].startswith(f"swarmtag calibrate --baseline {folder / 'small.toml'}")


def test_the_recorded_objective_is_the_reported_one_and_the_profile_reproduces_it(calibrated):
    folder, results = calibrated
    profile = read_profile_file(folder / "small.profile.toml")
    report = results[0]["report"]
    objective_text = f"{profile.calibration['objective']:.6g}"
    assert f"objective {objective_text} at the rounded point" in report
    assert f"at the rounded point {objective_text}." in report
    # Simulating the written profile gives that objective again, exactly (same runs, same seed).
    targets = load_baseline(str(folder / "small.toml"))
    (setup,) = targets.setups
    scenario = profile.scenario(setup.scenario)
    log = simulate(scenario, parse_policy("proximity"), seed=0, runs=setup.runs).carriers
    achieved = {
        setup.name: achieved_kpis(log, condition="proximity", setup=setup, simulated_runs=6)
    }
    assert objective(fit_rows(targets, achieved)) == profile.calibration["objective"]
    for kpi, value in achieved[setup.name].items():
        shown = "n/a" if value is None else f"{value:.4g}"
        assert f"| 3x7-short | {kpi} |" in report
        assert f"| {shown} |" in report


def test_a_rerun_simulates_nothing_and_writes_the_same_bytes(calibrated):
    folder, (first, second) = calibrated
    done = read_profile_file(folder / "small.profile.toml").calibration["evaluations_done"]
    assert second["profile"] == first["profile"]
    assert second["cache"] == first["cache"]  # nothing appended: every point came from the cache
    assert len(first["cache"]) <= done + 1  # the search, then the rounded point
    assert f"{done} search evaluations" in first["report"]
    assert f"0 simulated, {done + 1} from the cache" in second["report"]


def test_the_printed_table(calibrated, capsys):
    folder, _ = calibrated
    code, out, err = run(
        [
            "--baseline",
            str(folder / "small.toml"),
            "--profile",
            "base",
            "--out",
            str(folder / "small.profile.toml"),
            "--workers",
            "1",
        ],
        capsys,
    )
    assert (code, err) == (0, "")
    for column in ("set-up", "KPI", "target", "95 % CI", "achieved", "residual", "inside CI?"):
        assert column in out
    assert "fitted: timing.dock = " in out
    assert " 0 simulated, " in out
    assert f"wrote profile small: {folder / 'small.profile.toml'}" in out


def test_an_event_log_baseline_end_to_end(tmp_path, capsys):
    out_file = tmp_path / "lab.toml"
    argv = ["--baseline", str(example_trial_path()), "--profile", "base", "--out", str(out_file)]
    argv += ["--free", "timing.dock=0.5:10:log", "--runs", "2", "--evaluations", "2"]
    argv += ["--set", "time_unit=s", "--set", "urgency.model=static", "--workers", "1"]
    code, out, err = run(argv, capsys)
    assert (code, err) == (0, "")
    profile = read_profile_file(out_file)
    assert (profile.name, profile.values["time_unit"]) == ("lab", "s")
    assert profile.values["urgency"]["model"] == "static"
    assert profile.calibration["baseline_kind"] == "event log"
    assert profile.calibration["settings"] == {"time_unit": "s", "urgency.model": "static"}
    assert profile.calibration["runs"] == {"example_trial": 2}
    assert math.isfinite(profile.calibration["objective"])
    for kpi in ("p95_latency", "mean_latency", "throughput", "pa", "deliveries_per_run"):
        assert f"example_trial │ {kpi}" in out


@pytest.mark.parametrize(
    ("extra", "message"),
    [
        (["--evaluations", "0"], "--evaluations: 0 is not an integer in 1-5000"),
        (["--evaluations", "99999"], "--evaluations: 99999 is not an integer in 1-5000"),
        (["--runs", "0"], "--runs: 0 is not an integer in 1-10000"),
        (["--runs", "100000"], "--runs: 100000 is not an integer in 1-10000"),
        (["--free", "tick=0.2:0.1"], "--free tick: the bounds 0.2:0.1 are empty (need LO < HI)"),
        (["--free", "timing.dok=1:2"], "--free timing.dok: not a scenario key"),
        (["--free", "motion.collision_iterations=1:9"], "the setting is an integer (8)"),
        (["--free", "tick=0.01:0.2", "--set", "tick=0.2"], "--free tick: --set tick=... fixes"),
        (["--set", "ticks=900"], "--set ticks: set-up '3x7-short' of "),
        (["--set", "timing.dokk=2"], "--set: timing.dokk: unknown key"),
        (["--set", "timing.dock"], "--set: 'timing.dock' is not KEY=VALUE"),
        (["--condition", "proximity"], "--condition picks an event log's condition"),
        (["--seed", "-3"], "--seed: -3 is not an integer in 0-9223372036854775807"),
        (["--profile", "nope"], "profile 'nope': no such shipped profile"),
    ],
)
def test_refusals_are_one_line_before_any_work(tmp_path, capsys, monkeypatch, extra, message):
    def no_work(*args, **kwargs):
        raise AssertionError("simulated before refusing")

    monkeypatch.setattr(calibrate_cli, "calibrate", no_work)
    argv = ["--baseline", str(SMALL_TARGETS), "--out", str(tmp_path / "p.toml")]
    code, _, err = run([*argv, "--profile", "base", *extra], capsys)
    assert code == 2
    assert err.startswith("swarmtag: error: ")
    assert message in err
    assert err.count("\n") == 1
    assert not (tmp_path / "p.toml").exists()


def test_a_log_in_seconds_needs_a_profile_in_seconds(tmp_path, capsys):
    argv = ["--baseline", str(example_trial_path()), "--out", str(tmp_path / "p.toml")]
    code, _, err = run([*argv, "--profile", "base", "--free", "tick=0.05:0.2"], capsys)
    assert code == 2
    assert err == (
        f"swarmtag: error: {example_trial_path()} is in seconds but profile 'base' logs in "
        'ticks: use a profile with time_unit = "s" or --set time_unit=s\n'
    )


@pytest.mark.parametrize(
    ("out", "report", "message"),
    [
        ("missing/p.toml", None, "folder '{tmp}/missing' does not exist"),
        ("p.json", None, "--out: '{tmp}/p.json' must end in .toml"),
        ("p.toml", "missing/r.md", "folder '{tmp}/missing' does not exist"),
        ("p.toml", "r.txt", "--report: '{tmp}/r.txt' must end in .md"),
    ],
)
def test_output_paths_are_refused_first(tmp_path, capsys, monkeypatch, out, report, message):  # noqa: PLR0917
    monkeypatch.setattr(calibrate_cli, "load_baseline", lambda *a, **k: pytest.fail("read"))
    argv = ["--baseline", "lab", "--out", str(tmp_path / out)]
    if report:
        argv += ["--report", str(tmp_path / report)]
    code, _, err = run(argv, capsys)
    assert code == 2
    assert message.format(tmp=tmp_path) in err


def test_other_baselines_refused(tmp_path, capsys):
    for baseline, message in (
        ("nothing", "--baseline 'nothing': not a file, and no shipped baseline"),
        (str(tmp_path / "none.toml"), "none.toml: no such target file"),
        (str(tmp_path / "none.parquet"), "none.parquet: no such event log"),
    ):
        code, _, err = run(["--baseline", baseline, "--out", str(tmp_path / "p.toml")], capsys)
        assert code == 2
        assert message in err


def test_no_free_parameters(tmp_path, capsys):
    text = SMALL_TARGETS.read_text(encoding="utf-8")
    without = "\n".join(line for line in text.splitlines() if not line.startswith("free ="))
    (tmp_path / "t.toml").write_text(without, encoding="utf-8")
    argv = ["--baseline", str(tmp_path / "t.toml"), "--out", str(tmp_path / "p.toml")]
    code, _, err = run([*argv, "--profile", "base"], capsys)
    assert code == 2
    assert "no free parameters: give --free NAME=LO:HI" in err


def test_ctrl_c_stops_cleanly_and_says_how_to_resume(tmp_path, capsys, monkeypatch):
    def interrupted(*args, **kwargs):
        raise KeyboardInterrupt

    monkeypatch.setattr(calibrate_cli, "calibrate", interrupted)
    argv = [
        "--baseline",
        str(SMALL_TARGETS),
        "--profile",
        "base",
        "--out",
        str(tmp_path / "p.toml"),
    ]
    code, _, err = run(argv, capsys)
    assert code == 130
    assert f"are kept in {tmp_path / 'p.cache.jsonl'}; run the same command to resume" in err
    assert not (tmp_path / "p.toml").exists()
