"""Atomic file replacement."""

from __future__ import annotations

import errno
import os

import pytest

from swarmtag import _atomic
from swarmtag._atomic import WriteFailure, atomic_path, atomic_write_bytes, write_failure_in_text
from swarmtag.errors import OutputError
from tests.full_disk import REFUSALS


def test_replaces_and_honours_umask(tmp_path):
    path = tmp_path / "out.bin"
    old = os.umask(0o022)
    try:
        atomic_write_bytes(path, b"one")
        atomic_write_bytes(path, b"two")
    finally:
        os.umask(old)
    assert path.read_bytes() == b"two"
    assert path.stat().st_mode & 0o777 == 0o644
    assert [p.name for p in tmp_path.iterdir()] == ["out.bin"]


def test_error_inside_keeps_old_file_and_removes_temp(tmp_path):
    path = tmp_path / "out.bin"
    path.write_bytes(b"old")

    def write_half_then_fail() -> None:
        with atomic_path(path) as temp:
            temp.write_bytes(b"half")
            raise RuntimeError("boom")

    with pytest.raises(RuntimeError, match="boom"):
        write_half_then_fail()
    assert path.read_bytes() == b"old"
    assert [p.name for p in tmp_path.iterdir()] == ["out.bin"]


def test_missing_folder_is_an_error_not_a_new_folder(tmp_path):
    with pytest.raises(FileNotFoundError):
        atomic_write_bytes(tmp_path / "typo" / "out.bin", b"x")
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize(("code", "reason"), REFUSALS)
def test_a_write_the_device_refuses_names_the_target_and_leaves_it(tmp_path, code, reason):
    path = tmp_path / "out.bin"
    path.write_bytes(b"old")

    def write_half_then_refuse() -> None:
        with atomic_path(path) as temp:
            temp.write_bytes(b"half")
            raise OSError(code, os.strerror(code))

    with pytest.raises(WriteFailure) as refused:
        write_half_then_refuse()
    assert str(refused.value) == f"{reason} while writing {path}"
    assert isinstance(refused.value, OutputError)  # one line and exit 2 on the command line
    assert isinstance(refused.value, OSError)  # code guarding a save still sees an OSError
    assert refused.value.errno == code
    assert path.read_bytes() == b"old"
    assert [p.name for p in tmp_path.iterdir()] == ["out.bin"]


def test_a_refusal_while_flushing_is_named_too(tmp_path, monkeypatch):
    def refuse(fd: int) -> None:
        raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.setattr(_atomic.os, "fsync", refuse)
    with pytest.raises(WriteFailure, match=r"^no space left on device while writing .*out\.bin$"):
        atomic_write_bytes(tmp_path / "out.bin", b"x")
    assert list(tmp_path.iterdir()) == []


def test_other_errors_pass_unchanged(tmp_path):
    with pytest.raises(PermissionError), atomic_path(tmp_path / "out.bin"):
        raise PermissionError(errno.EACCES, "Permission denied")
    assert list(tmp_path.iterdir()) == []


def test_a_library_s_message_naming_a_refusal_is_read():
    text = 'Failed to commit: Could not write file "s.wal": No space left on device'
    failure = write_failure_in_text(text, "out/s.duckdb")
    assert failure is not None
    assert str(failure) == "no space left on device while writing out/s.duckdb"
    assert write_failure_in_text("Constraint Error: duplicate key", "x") is None
