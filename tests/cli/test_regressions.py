"""One test per bug the CLI fuzzer (tests/cli/test_fuzz.py) found: each was a traceback."""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest

from swarmtag._outputs import STAGING_PREFIX
from swarmtag.cli import main
from swarmtag.data import example_trial_path
from tests.cli.test_fuzz import TINY_TARGETS

LONG = "x" * 300
"""A name longer than any file system allows (ENAMETOOLONG), which Path.is_file() raises on."""


def run(capsys, *argv: str) -> tuple[int, str, str]:
    with pytest.raises(SystemExit) as exited:
        main(list(argv))
    out, err = capsys.readouterr()
    return int(exited.value.code or 0), out, err


@pytest.fixture
def work(tmp_path, monkeypatch) -> Path:
    """An empty working folder holding the example trial and the tiny targets, as cwd."""
    shutil.copy(example_trial_path(), tmp_path / "trial.csv")
    (tmp_path / "targets.toml").write_text(TINY_TARGETS, encoding="utf-8")
    monkeypatch.chdir(tmp_path)
    return tmp_path


def refused(capsys, folder: Path, *argv: str) -> str:
    """Run ``argv``: exit 2, one ``swarmtag: error:`` line, nothing new in ``folder``."""
    before = sorted(folder.rglob("*"))
    code, out, err = run(capsys, *argv)
    assert (code, out) == (2, ""), err
    assert err.startswith("swarmtag: error: ")
    assert err.count("\n") == 1
    assert err.endswith("\n")
    assert sorted(folder.rglob("*")) == before
    return err


def test_a_nul_byte_in_an_argument_is_refused(work, capsys):
    # click.Path's os.stat raised ValueError("embedded null byte") through the CLI.
    err = refused(capsys, work, "metrics", "trial.csv", "--markdown", "a\0b.md")
    assert "argument 4" in err
    assert "NUL byte" in err


def test_calibrate_with_an_empty_out_is_refused(work, capsys):
    # The default cache path was derived from --out before --out was checked:
    # Path("").with_name(...) raised ValueError.
    err = refused(capsys, work, "calibrate", "--baseline", "targets.toml", "--out", "")
    assert "--out" in err
    assert ".toml" in err


@pytest.mark.parametrize(
    "argv",
    [
        ["profiles", LONG],
        ["simulate", "--profile", LONG, "--runs", "1"],
        ["calibrate", "--baseline", "targets.toml", "--profile", LONG, "--out", "p.toml"],
        ["calibrate", "--baseline", LONG, "--out", "p.toml"],
        ["calibrate", "--baseline", LONG + ".csv", "--out", "p.toml"],
    ],
    ids=["profiles", "simulate-profile", "calibrate-profile", "calibrate-baseline", "baseline-log"],
)
def test_a_name_too_long_for_a_path_is_refused(work, capsys, argv):
    # Path(name).is_file() raised OSError(ENAMETOOLONG) where a name or a file is accepted.
    err = refused(capsys, work, *argv)
    assert "xxxxxxxx" in err


@pytest.mark.parametrize(
    "argv",
    [
        ["metrics", "trial.csv", "--figures", LONG],
        ["metrics", "trial.csv", "--markdown", f"{LONG}/tables.md"],
        ["calibrate", "--baseline", "targets.toml", "--out", "p.toml", "--cache", LONG],
    ],
    ids=["folder-output", "folder-of-a-file-output", "calibrate-cache"],
)
def test_an_output_path_too_long_is_refused(work, capsys, argv):
    # OutputPlan.folder / _check_folder and calibrate's cache check called Path.exists() and
    # Path.is_dir(), which raise OSError(ENAMETOOLONG) instead of returning False.
    err = refused(capsys, work, *argv)
    assert "cannot be checked (File name too long)" in err


@pytest.mark.parametrize("name", ["", "."])
def test_figures_into_the_current_folder(work, capsys, name):
    # "--figures ." (or "", which click reads as ".") staged its folder at the staging root
    # itself: Path(".").name is "", so mkdir raised FileExistsError.
    code, _, err = run(capsys, "metrics", "trial.csv", "--resamples", "20", "--figures", name)
    assert (code, err) == (0, "")
    assert sorted(p.name for p in work.glob("*.png")) == [
        "latency_curves.png",
        "pa_curves.png",
        "urgency_latency.png",
    ]
    assert not list(work.parent.glob(f"{STAGING_PREFIX}*"))
    assert not list(work.glob(f"{STAGING_PREFIX}*"))


def test_simulate_snapshot_without_a_file_name_is_refused(work, capsys):
    # The per-condition name of Path("") raised ValueError ("has an empty name").
    err = refused(capsys, work, "simulate", "--ticks", "5", "--runs", "1", "--snapshot", "")
    assert "--snapshot" in err
    assert ".png" in err


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["--out", "targets.toml"], "--out: 'targets.toml' is also an input (--baseline)"),
        (
            ["--out", "p.toml", "--cache", "targets.toml"],
            "--cache: 'targets.toml' is also an input",
        ),
        (["--out", "p.toml", "--cache", "p.toml"], "--cache: 'p.toml' is also an output (--out)"),
    ],
    ids=["out-is-baseline", "cache-is-baseline", "cache-is-out"],
)
def test_calibrate_never_writes_over_its_baseline(work, capsys, argv, message):
    # The baseline file was no planned input: --out targets.toml overwrote the target file
    # with the fitted profile, and --cache targets.toml appended cache lines to it.
    before = (work / "targets.toml").read_bytes()
    err = refused(capsys, work, "calibrate", "--baseline", "targets.toml", "--workers", "1", *argv)
    assert message in err
    assert (work / "targets.toml").read_bytes() == before


def test_draw_run_past_the_last_run_index_is_refused_before_work(work, capsys):
    # --draw-run accepted 2**53, one past the largest run index: the runs were simulated and
    # only then the redrawn run was refused, naming "run_offset" instead of the option.
    err = refused(capsys, work, "simulate", "--ticks", "5", "--runs", "1", "--draw-run",
                  str(2**53), "--trajectories", "t.npz")  # fmt: skip
    assert "--draw-run" in err
