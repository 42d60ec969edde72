"""Input files: only readable regular files are opened; the rest are refused in one line."""

from __future__ import annotations

import os

import pytest

from swarmtag._inputs import regular_file
from swarmtag._toml import read_toml
from swarmtag.errors import ConfigError, EventLogError, StudyError


def test_a_regular_file_is_accepted(tmp_path):
    path = tmp_path / "a.toml"
    path.write_text("x = 1\n")
    assert regular_file(path, what="study file", error=StudyError) == path


@pytest.mark.parametrize(
    ("make", "message"),
    [
        ("missing", "no such event log"),
        ("folder", "is a folder, not the event log"),
        ("fifo", "is not a regular file (a FIFO, socket or device); the event log must be one"),
    ],
)
def test_other_paths_are_refused_without_opening_them(tmp_path, make, message):
    path = tmp_path / "log"
    if make == "folder":
        path.mkdir()
    elif make == "fifo":
        os.mkfifo(path)  # opening it would block forever
    with pytest.raises(EventLogError) as error:
        regular_file(path, what="event log", error=EventLogError)
    assert str(error.value) == f"{path}: {message}"


def test_a_nul_byte_in_the_path_is_refused(tmp_path):
    with pytest.raises(ConfigError, match="not a valid path"):
        regular_file(f"{tmp_path}/a\0b", what="scenario file", error=ConfigError)


def test_toml_files_go_through_the_same_check(tmp_path):
    fifo = tmp_path / "scenario.toml"
    os.mkfifo(fifo)
    with pytest.raises(ConfigError, match="is not a regular file"):
        read_toml(fifo, what="scenario file", error=ConfigError)
