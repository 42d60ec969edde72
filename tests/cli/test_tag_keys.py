"""``swarmtag tag keygen --out FILE``, driven through click's CliRunner on the command itself."""

from __future__ import annotations

import os
import stat

import pytest
from click.testing import CliRunner

from swarmtag.cli.tag_keys import keygen_cmd
from swarmtag.tag import read_key_file


def _keygen(*args: str):
    return CliRunner().invoke(keygen_cmd, list(args))


def test_keygen_writes_a_private_key_file_and_never_prints_the_key(tmp_path):
    path = tmp_path / "site.key"
    result = _keygen("--out", str(path))
    assert result.exit_code == 0, result.output
    key = read_key_file(path)
    assert len(key) == 32
    if os.name == "posix":
        assert stat.S_IMODE(path.stat().st_mode) == 0o600
    shown = result.output + (result.stderr or "")
    assert key.hex() not in shown
    assert key.hex().upper() not in shown
    assert str(path) in result.output


def test_two_keys_differ(tmp_path):
    for name in ("a.key", "b.key"):
        assert _keygen("--out", str(tmp_path / name)).exit_code == 0
    assert read_key_file(tmp_path / "a.key") != read_key_file(tmp_path / "b.key")


def test_an_existing_file_is_refused_and_kept(tmp_path):
    path = tmp_path / "site.key"
    assert _keygen("--out", str(path)).exit_code == 0
    before = path.read_bytes()
    result = _keygen("--out", str(path))
    assert result.exit_code == 2
    assert "already exists; refusing to overwrite" in result.output
    assert str(path) in result.output
    assert path.read_bytes() == before
    assert before.decode().split("\n")[1] not in result.output


def test_a_missing_folder_is_refused(tmp_path):
    result = _keygen("--out", str(tmp_path / "missing" / "site.key"))
    assert result.exit_code == 2
    assert "does not exist" in result.output
    assert not (tmp_path / "missing").exists()


def test_a_folder_as_out_is_refused(tmp_path):
    result = _keygen("--out", str(tmp_path))
    assert result.exit_code == 2
    assert "is a directory" in result.output


@pytest.mark.parametrize("args", [[], ["--out"]])
def test_out_is_required(args):
    result = _keygen(*args)
    assert result.exit_code == 2
    assert "--out" in result.output


def test_help_names_the_command_and_the_promise():
    result = _keygen("--help")
    assert result.exit_code == 0
    assert "never printed" in " ".join(result.output.split())
    assert keygen_cmd.name == "keygen"
