"""The output plan: one rule for every output path, all outputs or none."""

from __future__ import annotations

import contextlib
import errno
import os
import shutil
import signal
import subprocess
import sys
from pathlib import Path

import pytest

from swarmtag._atomic import WriteFailure
from swarmtag._outputs import STAGING_PREFIX, OutputPlan
from swarmtag.errors import OutputError, StudyError


def names(folder: Path) -> list[str]:
    return sorted(str(p.relative_to(folder)) for p in folder.rglob("*"))


def write_then(plan: OutputPlan, targets: list[Path], problem: BaseException | None) -> None:
    """Stage ``targets`` with text, then raise ``problem`` (if any) inside the plan's writing."""
    with plan.writing() as stage:
        for target in targets:
            stage.path(target).write_text("new")
        if problem is not None:
            raise problem


def test_all_outputs_appear_together(tmp_path):
    plan = OutputPlan()
    a = plan.file("--a", tmp_path / "a.csv", suffixes=(".csv",))
    b = plan.file("--b", tmp_path / "b.md")
    figs = plan.folder("--figures", tmp_path / "figs")
    with plan.writing() as stage:
        stage.path(a).write_text("a")
        stage.path(b).write_text("b")
        (stage.path(figs) / "one.png").write_bytes(b"png")
        assert names(tmp_path)[0].startswith(STAGING_PREFIX)  # nothing in place yet
        assert not a.exists()
    assert names(tmp_path) == ["a.csv", "b.md", "figs", "figs/one.png"]


def test_a_failure_leaves_the_old_files_and_no_staging(tmp_path):
    (tmp_path / "a.csv").write_text("old")
    plan = OutputPlan()
    a = plan.file("--a", tmp_path / "a.csv")
    b = plan.file("--b", tmp_path / "b.csv")
    with pytest.raises(RuntimeError):
        write_then(plan, [a, b], RuntimeError())
    assert names(tmp_path) == ["a.csv"]
    assert (tmp_path / "a.csv").read_text() == "old"


def test_an_interrupt_while_working_leaves_nothing(tmp_path):
    plan = OutputPlan()
    a = plan.file("--a", tmp_path / "a.csv")
    with pytest.raises(KeyboardInterrupt):
        write_then(plan, [a], KeyboardInterrupt())
    assert names(tmp_path) == []


def test_an_output_that_was_not_written_fails_before_any_move(tmp_path):
    plan = OutputPlan()
    a = plan.file("--a", tmp_path / "a.csv")
    plan.file("--b", tmp_path / "b.csv")
    with pytest.raises(OutputError, match=r"not written: .*b\.csv"), plan.writing() as stage:
        stage.path(a).write_text("a")
    assert names(tmp_path) == []


def test_folder_outputs_merge_into_what_is_there(tmp_path):
    (tmp_path / "out" / "keep").mkdir(parents=True)
    (tmp_path / "out" / "keep" / "old.txt").write_text("old")
    plan = OutputPlan()
    out = plan.folder("DIR", tmp_path / "out")
    with plan.writing() as stage:
        (stage.path(out) / "keep").mkdir()
        (stage.path(out) / "keep" / "new.txt").write_text("new")
    assert names(tmp_path) == ["out", "out/keep", "out/keep/new.txt", "out/keep/old.txt"]


@pytest.mark.parametrize(
    ("make", "path", "suffixes", "message"),
    [
        (None, "missing/a.csv", (), "folder '{tmp}/missing' does not exist"),
        ("dir", "x.csv", (".csv",), "is a folder; give a file name"),
        ("fifo", "x.csv", (), "is not a regular file"),
        (None, "a.txt", (".csv", ".parquet"), "must end in .csv or .parquet"),
        ("file", "x.csv/a.csv", (), "folder '{tmp}/x.csv' is not a folder"),
    ],
)
def test_bad_file_paths_are_refused_when_planned(tmp_path, make, path, suffixes, message):
    target = tmp_path / "x.csv"
    if make == "dir":
        target.mkdir()
    elif make == "fifo":
        os.mkfifo(target)
    elif make == "file":
        target.write_text("")
    with pytest.raises(OutputError) as error:
        OutputPlan().file("--out", tmp_path / path, suffixes=suffixes)
    assert str(error.value).startswith(f"--out: '{tmp_path / path}'")
    assert message.format(tmp=tmp_path) in str(error.value)


def test_two_outputs_on_one_file_are_refused_whatever_the_spelling(tmp_path):
    (tmp_path / "sub").mkdir()
    plan = OutputPlan()
    plan.file("--events", tmp_path / "same.csv")
    with pytest.raises(OutputError, match=r"is also an output \(--events\)"):
        plan.file("--event-table", tmp_path / "sub" / ".." / "same.csv")


def test_an_output_on_an_input_is_refused(tmp_path):
    plan = OutputPlan()
    plan.input("EVENTS", tmp_path / "log.csv")
    with pytest.raises(OutputError, match=r"is also an input \(EVENTS\)"):
        plan.file("--out", tmp_path / "log.csv")


def test_folder_output_rules(tmp_path):
    (tmp_path / "f").write_text("")
    with pytest.raises(OutputError, match="is a file; give a folder"):
        OutputPlan().folder("--figures", tmp_path / "f")
    with pytest.raises(OutputError, match="does not exist"):
        OutputPlan().folder("--figures", tmp_path / "a" / "b")


def test_an_unwritable_folder_is_refused_before_any_work(unwritable_dir):
    folder = unwritable_dir
    plan = OutputPlan(error=StudyError)
    plan.file("--html", folder / "x.html")
    worked = []
    with pytest.raises(StudyError, match="cannot be written in folder"), plan.writing():
        worked.append(True)
    assert worked == []


def test_sigint_during_the_final_moves_is_held_until_all_are_in_place(tmp_path, monkeypatch):
    plan = OutputPlan()
    targets = [plan.file(f"--o{i}", tmp_path / f"{i}.txt") for i in range(20)]
    original = Path.replace

    def replace_and_interrupt(self: Path, target: Path) -> Path:
        os.kill(os.getpid(), signal.SIGINT)  # arrives mid-commit: held back until the end
        return original(self, target)

    monkeypatch.setattr(Path, "replace", replace_and_interrupt)
    with pytest.raises(KeyboardInterrupt):
        write_then(plan, targets, None)
    monkeypatch.undo()
    assert names(tmp_path) == sorted(f"{i}.txt" for i in range(20))


def test_sigint_while_the_staging_folder_is_removed_still_removes_it(tmp_path, monkeypatch):
    plan = OutputPlan()
    target = plan.file("--out", tmp_path / "a.txt")
    original = shutil.rmtree

    def interrupt_then_remove(path: Path, *, ignore_errors: bool) -> None:
        os.kill(os.getpid(), signal.SIGINT)  # held back until every staging folder is gone
        original(path, ignore_errors=ignore_errors)

    monkeypatch.setattr(shutil, "rmtree", interrupt_then_remove)
    with pytest.raises(KeyboardInterrupt):
        write_then(plan, [target], RuntimeError("the command failed"))
    monkeypatch.undo()
    assert names(tmp_path) == []


def test_a_staging_folder_whose_removal_never_ran_goes_at_exit(tmp_path):
    # A Ctrl-C as the ``with`` block ends, before the context manager's exit runs, leaves the
    # generator suspended; here it is never finalized (a leaked reference), as when a traceback
    # holds it: the process's exit removes its staging folder all the same.
    script = (
        "import ctypes, sys, pathlib\n"
        "from swarmtag._outputs import OutputPlan\n"
        "plan = OutputPlan()\n"
        "target = plan.file('--out', pathlib.Path(sys.argv[1]) / 'a.txt')\n"
        "writing = plan.writing()\n"
        "stage = writing.__enter__()\n"
        "ctypes.pythonapi.Py_IncRef(ctypes.py_object(writing))\n"
        "stage.path(target).write_text('half')\n"
        "print(len(list(pathlib.Path(sys.argv[1]).iterdir())))\n"
        "raise KeyboardInterrupt\n"
    )
    done = subprocess.run(
        [sys.executable, "-c", script, str(tmp_path)], capture_output=True, text=True, check=False
    )
    assert done.stdout.strip() == "1", done.stderr  # the staging folder existed
    assert "KeyboardInterrupt" in done.stderr
    assert names(tmp_path) == []


@pytest.mark.usefixtures("no_resent_interrupt")
def test_outputs_computed_after_a_swallowed_interrupt_are_not_kept(tmp_path):
    from swarmtag import _interrupt

    plan = OutputPlan()
    target = plan.file("--out", tmp_path / "a.txt")
    restore = _interrupt.install()
    try:

        def work() -> None:
            with plan.writing() as stage:
                stage.path(target).write_text("half-computed")
                with contextlib.suppress(KeyboardInterrupt):  # as a library might
                    os.kill(os.getpid(), signal.SIGINT)

        with pytest.raises(KeyboardInterrupt):
            work()
    finally:
        restore()
    assert names(tmp_path) == []


@pytest.mark.parametrize(
    ("code", "reason"),
    [
        (errno.ENOSPC, "no space left on device"),
        (errno.EDQUOT, "disk quota exceeded"),
        (errno.EROFS, "read-only file system"),
        (errno.EFBIG, "file too large"),
        (errno.EIO, "input/output error"),
    ],
)
def test_a_staged_write_the_device_refuses_names_the_target(tmp_path, code, reason):
    (tmp_path / "a.csv").write_text("old")
    plan = OutputPlan()
    a = plan.file("--a", tmp_path / "a.csv")
    b = plan.file("--b", tmp_path / "b.md")

    def write_then_refuse() -> None:
        with plan.writing() as stage:
            stage.path(a).write_text("new")
            with stage.path(b).open("w"):  # a library writing straight to the staged file
                raise OSError(code, os.strerror(code))  # as a write() raises it: no file named

    with pytest.raises(WriteFailure) as refused:
        write_then_refuse()
    assert str(refused.value) == f"{reason} while writing {b}"
    assert names(tmp_path) == ["a.csv"]
    assert (tmp_path / "a.csv").read_text() == "old"


def test_a_refused_file_in_a_staged_folder_is_named_by_its_target(tmp_path):
    plan = OutputPlan()
    figures = plan.folder("--figures", tmp_path / "figs")

    def refuse_a_file_in_the_folder() -> None:
        with plan.writing() as stage:
            staged = stage.path(figures) / "one.png"
            raise OSError(errno.ENOSPC, "No space left on device", str(staged))

    with pytest.raises(WriteFailure) as refused:
        refuse_a_file_in_the_folder()
    assert str(refused.value) == f"no space left on device while writing {figures / 'one.png'}"
    assert names(tmp_path) == []


def test_a_writer_s_own_error_for_a_refused_write_becomes_the_one_message(tmp_path, monkeypatch):
    from swarmtag import _atomic
    from swarmtag.io import CarrierLog, write_event_log

    def refuse(fd: int) -> None:
        raise OSError(errno.EDQUOT, "Disk quota exceeded")

    log = CarrierLog(
        condition=["p"],
        run=[0],
        seed=[0],
        carrier=[4],
        urgency0=[7],
        order_time=[0.0],
        pickup_time=[1.0],
        delivery_time=[2.0],
        robot=[1],
    )
    plan = OutputPlan()
    target = plan.file("--events", tmp_path / "e.csv")
    monkeypatch.setattr(_atomic.os, "fsync", refuse)
    with pytest.raises(WriteFailure) as refused, plan.writing() as stage:
        write_event_log(log, stage.path(target))  # the CSV writer wraps it as its own error
    assert str(refused.value) == f"disk quota exceeded while writing {target}"
    assert names(tmp_path) == []


def test_other_errors_that_name_a_staged_file_name_its_target(tmp_path):
    plan = OutputPlan()
    target = plan.file("--out", tmp_path / "a.txt")

    def refuse_naming_the_staged_file() -> None:
        with plan.writing() as stage:
            msg = f"{stage.path(target)}: cannot write (Permission denied)"
            raise StudyError(msg)

    with pytest.raises(StudyError) as refused:
        refuse_naming_the_staged_file()
    assert str(refused.value) == f"{target}: cannot write (Permission denied)"
    assert STAGING_PREFIX not in str(refused.value)
