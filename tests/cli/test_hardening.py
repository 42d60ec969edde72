"""Regression tests for every case of the hardening issue: one line, exit 2, nothing written."""

from __future__ import annotations

import os
import time
from pathlib import Path

import pytest

from swarmtag.cli import main
from swarmtag.data import example_trial_path
from swarmtag.io import read_event_log

SMALL = ["--profile", "base", "--ticks", "200", "--resamples", "100", "--no-progress"]
HUGE = "99999999999999999999999999"


def run(capsys, *argv: str) -> tuple[int, str, str]:
    with pytest.raises(SystemExit) as exited:
        main(list(argv))
    out, err = capsys.readouterr()
    return int(exited.value.code or 0), out, err


def refused(capsys, folder: Path, *argv: str) -> str:
    """Run ``argv``; assert exit 2, one stderr line, no traceback and no new file in ``folder``."""
    before = sorted(folder.rglob("*"))
    code, out, err = run(capsys, *argv)
    assert code == 2, err
    assert out == ""
    assert len(err.splitlines()) == 1
    assert err.startswith("swarmtag: error: ")
    assert "Traceback" not in err
    assert sorted(folder.rglob("*")) == before
    return err


def edited_log(tmp_path: Path, column: str, row: int, value: str) -> Path:
    """The example trial with one cell replaced, written as CSV text."""
    lines = example_trial_path().read_text().splitlines()
    header = lines[0].split(",")
    cells = lines[row + 1].split(",")
    cells[header.index(column)] = value
    lines[row + 1] = ",".join(cells)
    path = tmp_path / "edited.csv"
    path.write_text("\n".join(lines) + "\n")
    return path


# --- numbers at the edges ---------------------------------------------------------------


@pytest.mark.parametrize("extra", [[], ["--json"]])
def test_a_time_of_1e308_is_refused(tmp_path, capsys, extra):
    log = edited_log(tmp_path, "delivery_time", 0, "1e308")
    err = refused(capsys, tmp_path, "metrics", str(log), *extra)
    assert "delivery_time" in err
    assert "1e+12" in err


@pytest.mark.parametrize("option", ["--seed", "--run-offset"])
def test_huge_seed_or_run_offset_is_refused(tmp_path, capsys, option):
    err = refused(capsys, tmp_path, "simulate", *SMALL, option, HUGE)
    assert option in err


def test_huge_metrics_seed_is_refused(tmp_path, capsys):
    refused(capsys, tmp_path, "metrics", str(example_trial_path()), "--seed", HUGE)


@pytest.mark.parametrize(
    ("setting", "message"),
    [
        ("tick=1e-300", "tick: 1e-300 is not a number in [1e-06, 3600]"),
        ("arena.size=1e308", "arena.size: 1e+308 is not a number in (0, 100000]"),
        ("timing.dock=1e7", "timing.dock: 1e+07 s is 1e+09 ticks of 0.01 s"),
        ("realism.status_delay=100000000", "realism.status_delay: 100000000 ticks is longer"),
    ],
)
def test_scenario_values_at_the_edges_are_refused(tmp_path, capsys, setting, message):
    err = refused(capsys, tmp_path, "simulate", *SMALL, "--tick", "0.01", "--set", setting)
    assert message in err


def test_study_with_huge_seed_is_refused(tmp_path, capsys):
    study = tmp_path / "s.toml"
    study.write_text(
        'name = "s"\nconditions = ["proximity"]\nruns = 2\nseed = 99999999999999999999\n'
    )
    err = refused(capsys, tmp_path, "study", "run", str(study), "--out", str(tmp_path / "out"))
    assert "seed: 99999999999999999999 is not an integer in 0-9223372036854775807" in err


# --- unbounded work ---------------------------------------------------------------------


@pytest.mark.parametrize("resamples", ["1000000000", "20000000"])
def test_resamples_that_cannot_fit_are_refused_with_estimate_and_limit(
    tmp_path, capsys, monkeypatch, resamples
):
    monkeypatch.setenv("SWARMTAG_MEMORY_LIMIT", "1GiB")
    err = refused(capsys, tmp_path, "metrics", str(example_trial_path()), "--resamples", resamples)
    assert f"--resamples {resamples}" in err
    assert "1.0 GiB is available" in err


def test_ten_billion_runs_are_refused_at_once(tmp_path, capsys):
    started = time.perf_counter()
    err = refused(capsys, tmp_path, "simulate", "--runs", "10000000000")
    assert "--runs 10000000000" in err
    assert "TiB of memory" in err
    assert time.perf_counter() - started < 30  # refused before simulating, not after


def test_a_study_of_1e11_runs_is_refused(tmp_path, capsys):
    study = tmp_path / "s.toml"
    study.write_text('name = "s"\nconditions = ["proximity"]\nruns = 100000000000\n')
    err = refused(capsys, tmp_path, "study", "run", str(study), "--out", str(tmp_path / "out"))
    assert "needs about" in err


# --- outputs ------------------------------------------------------------------------------


def test_markdown_onto_an_existing_folder_is_refused(tmp_path, capsys):
    (tmp_path / "tables.md").mkdir()
    err = refused(
        capsys,
        tmp_path,
        "metrics",
        str(example_trial_path()),
        "--markdown",
        str(tmp_path / "tables.md"),
    )
    assert "is a folder" in err


def test_an_unwritable_html_refuses_before_writing_the_markdown(tmp_path, capsys, unwritable_dir):
    bad = unwritable_dir
    err = refused(
        capsys, tmp_path, "metrics", str(example_trial_path()),
        "--markdown", str(tmp_path / "ok.md"), "--html", str(bad / "x.html"),
    )  # fmt: skip
    assert "--html" in err
    assert not (tmp_path / "ok.md").exists()


def test_an_unwritable_snapshot_refuses_before_simulating(tmp_path, capsys, unwritable_dir):
    bad = unwritable_dir
    err = refused(
        capsys, tmp_path, "simulate", *SMALL, "--runs", "1",
        "--events", str(tmp_path / "e.csv"), "--snapshot", str(bad / "a.png"),
    )  # fmt: skip
    assert "--snapshot" in err


def test_an_unwritable_study_folder_is_refused(tmp_path, capsys, unwritable_dir):
    study = tmp_path / "s.toml"
    study.write_text('name = "s"\nconditions = ["proximity"]\nruns = 1\nticks = 50\n')
    err = refused(capsys, tmp_path, "study", "run", str(study), "--out", str(unwritable_dir / "o"))
    assert "--out" in err


def test_two_outputs_on_one_file_are_refused(tmp_path, capsys):
    same = str(tmp_path / "same.csv")
    err = refused(
        capsys, tmp_path, "simulate", *SMALL, "--runs", "1", "--events", same, "--event-table", same
    )
    assert "is also an output (--events)" in err


def test_figures_never_create_missing_parents(tmp_path, capsys):
    err = refused(
        capsys,
        tmp_path,
        "metrics",
        str(example_trial_path()),
        "--figures",
        str(tmp_path / "a" / "b"),
    )
    assert "does not exist" in err


def test_a_calibrated_profile_may_not_overwrite_its_base_profile(tmp_path, capsys):
    from swarmtag.sim.config import profiles

    base = tmp_path / "mine.toml"
    base.write_bytes((Path(profiles.__file__).parent / "presets" / "paper-sim.toml").read_bytes())
    err = refused(
        capsys, tmp_path, "calibrate", "--baseline", "paper-sim",
        "--profile", str(base), "--out", str(base),
    )  # fmt: skip
    assert "is also an input (--profile)" in err


# --- inputs -------------------------------------------------------------------------------


def test_order_after_delivery_is_refused(tmp_path, capsys):
    log = read_event_log(example_trial_path())
    lines = example_trial_path().read_text().splitlines()
    header = lines[0].split(",")
    cells = lines[1].split(",")
    cells[header.index("order_time")] = str(float(log.delivery_time[0]) + 100.0)
    path = tmp_path / "late.csv"
    path.write_text("\n".join([lines[0], ",".join(cells), *lines[2:]]) + "\n")
    err = refused(capsys, tmp_path, "metrics", str(path))
    assert "order_time" in err


def test_a_nul_byte_in_a_number_is_refused(tmp_path, capsys):
    log = edited_log(tmp_path, "delivery_time", 0, "12\0")
    err = refused(capsys, tmp_path, "metrics", str(log))
    assert "NUL" in err


def test_a_fifo_as_the_event_log_is_refused_without_blocking(tmp_path, capsys):
    fifo = tmp_path / "log.csv"
    os.mkfifo(fifo)
    err = refused(capsys, tmp_path, "metrics", str(fifo))
    assert "is not a regular file" in err


def test_an_event_log_too_large_for_memory_is_refused_before_reading(tmp_path, capsys, monkeypatch):
    monkeypatch.setenv("SWARMTAG_MEMORY_LIMIT", "100KiB")
    err = refused(capsys, tmp_path, "metrics", str(example_trial_path()))
    assert "example_trial.csv (7.4 KiB) needs about" in err


@pytest.mark.parametrize(
    "argv",
    [
        ["study", "run", "x" * 300, "--workers", "1"],
        ["study", "report", "x" * 300],
        ["study", "run", "--out", "x" * 300, "--workers", "1", "preliminary-sweep"],
        ["reproduce", "--study", "x" * 300],
    ],
)
def test_names_too_long_for_a_path_are_one_line(tmp_path, capsys, monkeypatch, argv):
    monkeypatch.chdir(tmp_path)
    err = refused(capsys, tmp_path, *argv)
    assert "xxx" in err


# --- TOML inputs: bounded size and nesting on every surface (issue 35) ---------------------

DEEP_TOML = {
    "arrays": "a = " + "[" * 400 + "]" * 400 + "\n",
    "inline-tables": "a = " + "{b = " * 400 + "1" + "}" * 400 + "\n",
    "dotted-header": "[[" + ".".join(["a"] * 400) + "]]\nx = 1\n",
}
"""About a kilobyte each: the first two raised RecursionError (a traceback, exit 1)."""
TOML_SURFACES = {
    "simulate --profile": (None, "simulate --profile {f} --ticks 10 --runs 1"),
    "simulate --config": (None, "simulate --config {f} --ticks 10 --runs 1"),
    "simulate --set": (None, "simulate --ticks 10 --runs 1 --set k={v}"),
    "study run": (None, "study run {f} --out out --workers 1"),
    "study report": (None, "study report rep --study {f}"),
    "reproduce --study": (None, "reproduce --study {f} --out out --workers 1"),
    "calibrate --baseline": (None, "calibrate --baseline {f} --free tick=0.02:0.2 --out p.toml"),
    "calibrate --profile": (None, "calibrate --baseline lab --profile {f} --out p.toml"),
    "calibrate --set": (None, "calibrate --baseline lab --out p.toml --set k={v}"),
    "profiles FILE": (None, "profiles {f}"),
    "log import --mapping": ("rosbags", "log import trial.mcap --mapping {f} --events e.csv"),
    "aruco render --camera": (
        "cv2",
        "aruco render --camera {f} --marker 1 --distance 0.5 --bearing 0 --out i.png",
    ),
    "aruco detect --camera": ("cv2", "aruco detect image.png --camera {f}"),
}
"""Every command-line option that reads TOML: the extra it needs, and its argv."""


def toml_argv(tmp_path: Path, surface: str, text: str) -> list[str]:
    """``surface``'s argv with ``text`` as its TOML file (or ``--set`` value), in ``tmp_path``."""
    extra, argv = TOML_SURFACES[surface]
    if extra is not None:
        pytest.importorskip(extra)
    path = tmp_path / "input.toml"
    path.write_text(text)
    (tmp_path / "trial.mcap").write_bytes(b"")
    (tmp_path / "image.png").write_bytes(b"")
    value = text.partition(" = ")[2].strip()  # the value of 'a = ...' for --set
    return [arg.replace("{f}", str(path)).replace("{v}", value) for arg in argv.split()]


@pytest.mark.parametrize(
    ("surface", "form"),
    [
        (surface, form)
        for surface in TOML_SURFACES
        for form in DEEP_TOML
        if not (surface.endswith("--set") and form == "dotted-header")  # --set takes a value
    ],
)
def test_deeply_nested_toml_is_one_line_on_every_surface(
    tmp_path, capsys, monkeypatch, surface, form
):
    monkeypatch.chdir(tmp_path)
    argv = toml_argv(tmp_path, surface, DEEP_TOML[form])
    err = refused(capsys, tmp_path, *argv)
    assert "nested more than 32 levels deep" in err


@pytest.mark.parametrize("surface", [s for s in TOML_SURFACES if not s.endswith("--set")])
def test_an_oversize_toml_file_is_one_line_on_every_surface(tmp_path, capsys, monkeypatch, surface):
    monkeypatch.chdir(tmp_path)
    argv = toml_argv(tmp_path, surface, "# " + "x" * (1 << 20) + "\nname = 'big'\n")
    err = refused(capsys, tmp_path, *argv)
    assert "larger than 1024 KiB" in err


def test_a_set_key_of_two_thousand_parts_is_one_line(tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    key = ".".join(["a"] * 2000)
    err = refused(capsys, tmp_path, "simulate", *SMALL, "--set", f"{key}=1")
    assert "has 2000 dotted parts; at most 32" in err


# --- studies checked before any work (issue 35) -------------------------------------------


def test_a_warmup_past_the_run_end_is_refused_before_any_run(tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    study = tmp_path / "w.toml"  # the defaults: a 60 s warm-up is tick 3103 of 3000
    study.write_text(
        'name = "w"\nconditions = ["proximity"]\nruns = 2\n[scales.s]\nwarehouse = {}\n'
    )
    started = time.perf_counter()
    err = refused(capsys, tmp_path, "study", "run", str(study), "--out", "out", "--workers", "1")
    assert (
        "scales.s: warehouse.warmup: 60 s is tick 3103, not before the run's end at tick 3000"
        in err
    )
    assert time.perf_counter() - started < 3  # nothing simulated
    assert not (tmp_path / "out").exists()


def test_a_study_name_too_long_for_a_folder_is_refused_before_writing(
    tmp_path, capsys, monkeypatch
):
    monkeypatch.chdir(tmp_path)
    study = tmp_path / "s.toml"
    study.write_text(f'name = "{"x" * 300}"\nconditions = ["proximity"]\nruns = 1\nticks = 50\n')
    err = refused(capsys, tmp_path, "study", "run", str(study), "--out", "out", "--workers", "1")
    assert (
        "name: 'xxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxx'... is 300 characters long; at most 100"
        in err
    )
    assert not (tmp_path / "out").exists()
