"""A full disk on every writing command: one line naming the file, exit 2, nothing left behind.

Each command runs against a real tmpfs filled to its last byte (root only;
skipped elsewhere), and once more with the device's refusal injected, which
needs no root. The target a command would replace must be left exactly as
it was, and no staging folder or temporary file may remain.
"""

from __future__ import annotations

import errno
import os
from pathlib import Path

import pytest

from swarmtag import _atomic
from swarmtag.cli import main
from swarmtag.data import example_trial_path
from tests.full_disk import FILLER, REFUSALS, fill, tmpfs

EXAMPLE = str(example_trial_path())
SIMULATE = ["simulate", "--runs", "1", "--ticks", "200", "--condition", "proximity"]
SIMULATE += ["--backend", "reference", "--resamples", "50", "--no-progress"]
METRICS = ["metrics", EXAMPLE, "--resamples", "50"]
STUDY = "name = 'small'\nconditions = ['proximity']\nruns = 2\nticks = 100\nresamples = 20\n"
STUDY += "profile = 'base'\n[scenario]\nrobots = 2\ncarriers = 3\n"

# (what, the arguments with OUT for the output, the output's name, an extra it needs)
COMMANDS = [
    ("metrics --markdown", [*METRICS, "--markdown", "OUT"], "r.md", None),
    ("metrics --latex", [*METRICS, "--latex", "OUT"], "r.tex", None),
    ("metrics --html", [*METRICS, "--html", "OUT"], "r.html", "matplotlib"),
    ("metrics --figures", [*METRICS, "--figures", "OUT"], "figures", "matplotlib"),
    ("simulate --events csv", [*SIMULATE, "--events", "OUT"], "e.csv", None),
    ("simulate --events parquet", [*SIMULATE, "--events", "OUT"], "e.parquet", "pyarrow"),
    ("simulate --event-table", [*SIMULATE, "--event-table", "OUT"], "t.csv", None),
    ("simulate --snapshot", [*SIMULATE, "--snapshot", "OUT"], "s.png", "matplotlib"),
    ("simulate --animate", [*SIMULATE, "--animate", "OUT"], "a.gif", "matplotlib"),
    ("simulate --trajectories", [*SIMULATE, "--trajectories", "OUT"], "t.npz", None),
    ("simulate --mcap", [*SIMULATE, "--mcap", "OUT"], "m.mcap", "rosbags"),
    (
        "aruco render",
        ["aruco", "render", "--marker", "3", "--distance", "1", "--bearing", "0", "--out", "OUT"],
        "r.png",
        "cv2",
    ),
    (
        "tag render",
        [
            *("tag", "render", "--urgency", "3", "--status", "idle", "--destination", "1"),
            *("--marker", "2", "--out", "OUT"),
        ],
        "e.png",
        "PIL",
    ),
    ("robot tree", ["robot", "tree", "--out", "OUT"], "tree", "py_trees"),
]


def run(capsys: pytest.CaptureFixture[str], argv: list[str]) -> tuple[int, str]:
    with pytest.raises(SystemExit) as exited:
        main(argv)
    return int(exited.value.code or 0), capsys.readouterr().err


def everything(folder: Path) -> dict[str, bytes | None]:
    """Every path under ``folder`` with a file's bytes (None for a folder)."""
    return {
        str(p.relative_to(folder)): None if p.is_dir() else p.read_bytes()
        for p in sorted(folder.rglob("*"))
        if p.name != FILLER
    }


def old_target(folder: Path, name: str) -> Path:
    """The output's target, already there with old content (a folder output: an old file in it)."""
    target = folder / name
    if "." in name:
        target.write_bytes(b"old\n")
    else:
        target.mkdir()
        (target / "old.txt").write_bytes(b"old\n")
    return target


def refused_in_one_line(code: int, err: str, target: Path) -> None:
    assert code == 2, err
    assert "Traceback" not in err
    assert len(err.splitlines()) == 1, err
    prefix = f"swarmtag: error: no space left on device while writing {target}"
    assert err.startswith(prefix), err


@pytest.fixture
def device(tmp_path: Path):
    with tmpfs(tmp_path / "device", "2m") as folder:
        yield folder


@pytest.mark.parametrize(("what", "argv", "name", "extra"), COMMANDS, ids=[c[0] for c in COMMANDS])
def test_a_full_disk_is_one_line_and_leaves_everything_as_it_was(  # noqa: PLR0917 - the cases
    device, capsys, what, argv, name, extra
):
    if extra is not None:
        pytest.importorskip(extra)
    target = old_target(device, name)
    fill(device)
    before = everything(device)
    code, err = run(capsys, [str(target) if word == "OUT" else word for word in argv])
    refused_in_one_line(code, err, target)
    assert everything(device) == before, what


def test_log_import_on_a_full_disk(device, tmp_path, capsys):
    pytest.importorskip("rosbags")
    from tests.io.bag_builders import TOPICS, lab_session, write_bag

    bag = write_bag(tmp_path / "session", "sqlite3", TOPICS, lab_session())
    target = old_target(device, "events.csv")
    fill(device)
    before = everything(device)
    code, err = run(capsys, ["log", "import", str(bag), "--events", str(target)])
    refused_in_one_line(code, err, target)
    assert everything(device) == before


@pytest.mark.parametrize("command", ["study run", "reproduce"])
def test_a_study_on_a_full_disk_names_its_store_and_leaves_nothing(
    device, tmp_path, capsys, command
):
    study = tmp_path / "study.toml"
    study.write_text(STUDY, encoding="utf-8")
    out = device / "out"
    fill(device)
    before = everything(device)
    head = ["study", "run", str(study)] if command == "study run" else ["reproduce", "--study"]
    argv = [*head, *([str(study)] if command == "reproduce" else [])]
    argv += ["--out", str(out), "--workers", "1", "--backend", "reference", "--no-progress"]
    code, err = run(capsys, argv)
    refused_in_one_line(code, err, out / "results.duckdb")
    assert everything(device) == before


def test_study_report_on_a_full_disk(device, tmp_path, capsys):
    study = tmp_path / "study.toml"
    study.write_text(STUDY, encoding="utf-8")
    out = device / "out"
    argv = ["study", "run", str(study), "--out", str(out), "--workers", "1"]
    assert run(capsys, [*argv, "--backend", "reference", "--no-progress"])[0] == 0
    fill(device)
    before = everything(device)
    code, err = run(capsys, ["study", "report", str(out), "--study", str(study)])
    assert code == 2, err
    assert len(err.splitlines()) == 1, err
    assert err.startswith(f"swarmtag: error: no space left on device while writing {out}/"), err
    assert everything(device) == before


def test_calibrate_on_a_full_disk_names_its_profile(device, tmp_path, capsys):
    # the cache of evaluated points lives elsewhere: it is kept on purpose (resumable)
    target = old_target(device, "fit.toml")
    fill(device)
    before = everything(device)
    argv = ["calibrate", "--baseline", "paper-sim", "--free", "camera.range=0.5:2"]
    argv += ["--evaluations", "2", "--runs", "1", "--workers", "1", "--no-progress"]
    argv += ["--cache", str(tmp_path / "fit.cache.jsonl"), "--out", str(target)]
    code, err = run(capsys, argv)
    assert code == 2, err
    lines = err.splitlines()
    assert lines[-1] == f"swarmtag: error: no space left on device while writing {target}", err
    assert all(not line.startswith("swarmtag: error:") for line in lines[:-1]), err
    assert everything(device) == before


def test_tag_write_with_its_counters_on_a_full_disk_sends_nothing(device, tmp_path, capsys):
    pytest.importorskip("bleak")
    from swarmtag.tag import (
        FileStore,
        TagModel,
        TagState,
        TagStatus,
        derive_robot_key,
        generate_site_key,
        read_key_file,
        write_key_file,
        write_robot_key_file,
    )

    site = write_key_file(tmp_path / "site.key", generate_site_key())
    site_key = read_key_file(site)
    write_robot_key_file(tmp_path / "robot.key", 7, derive_robot_key(site_key, 7))
    waiting = TagState(urgency=5, status=TagStatus.AWAITING_PICKUP, destination=2, marker=12)
    state = tmp_path / "tag.state"
    TagModel.provision(waiting, site_key=site_key, store=FileStore(state))
    kept = state.read_bytes()
    counters = device / "robot.counters"
    fill(device)
    before = everything(device)
    code, err = run(capsys, [
        "tag", "write", "aa:bb:cc:dd:ee:01", "--key-file", str(tmp_path / "robot.key"),
        "--writer", "7", "--role", "robot", "--status", "picked_up", "--counter-file",
        str(counters), "--backend", "loopback", "--loopback-state", str(state),
        "--loopback-key", str(site),
    ])  # fmt: skip
    assert code == 2, err
    assert len(err.splitlines()) == 1, err
    assert err == (
        f"swarmtag: error: cannot save counter file {counters}: no space left on device; "
        "nothing was sent\n"
    )
    assert everything(device) == before
    assert state.read_bytes() == kept  # the tag never heard the write


# --- the device's refusal injected: no root needed -----------------------------------------


@pytest.mark.parametrize(("code", "reason"), REFUSALS)
@pytest.mark.parametrize("option", ["--markdown", "--latex"])
def test_a_refused_write_is_one_line_naming_the_target(  # noqa: PLR0917 - the cases
    tmp_path, capsys, monkeypatch, code, reason, option
):
    target = tmp_path / ("r.md" if option == "--markdown" else "r.tex")
    target.write_bytes(b"old\n")

    def refuse(fd: int) -> None:
        raise OSError(code, os.strerror(code))

    monkeypatch.setattr(_atomic.os, "fsync", refuse)
    status, err = run(capsys, [*METRICS, option, str(target)])
    assert status == 2, err
    assert err == f"swarmtag: error: {reason} while writing {target}\n"
    assert everything(tmp_path) == {target.name: b"old\n"}


def test_an_event_log_refused_by_the_device_names_the_target_not_the_staging(
    tmp_path, capsys, monkeypatch
):
    target = tmp_path / "e.csv"

    def refuse(fd: int) -> None:
        raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.setattr(_atomic.os, "fsync", refuse)
    status, err = run(capsys, [*SIMULATE, "--events", str(target)])
    assert status == 2, err
    assert err == f"swarmtag: error: no space left on device while writing {target}\n"
    assert everything(tmp_path) == {}
