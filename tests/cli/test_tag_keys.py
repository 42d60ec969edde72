"""``swarmtag tag keygen [--role R --from SITE.key] --out FILE``, through click's CliRunner."""

from __future__ import annotations

import os
import stat

import pytest
from click.testing import CliRunner

from swarmtag.cli.tag_keys import keygen_cmd
from swarmtag.tag import (
    Role,
    derive_robot_key,
    derive_role_key,
    read_key_file,
    read_role_key_file,
    read_writer_key_file,
)


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


# --- role key files: keygen --role ROLE --from SITE.key --------------------------------------


@pytest.mark.parametrize(("role", "extra"), [("robot", "--shared"), ("operator", None)])
def test_keygen_derives_a_role_key_file_and_never_prints_it(tmp_path, role, extra):
    site = tmp_path / "site.key"
    assert _keygen("--out", str(site)).exit_code == 0
    out = tmp_path / f"{role}.key"
    flags = [extra] if extra else []
    result = _keygen("--role", role, *flags, "--from", str(site), "--out", str(out))
    assert result.exit_code == 0, result.output
    found, key = read_role_key_file(out)
    assert found is Role[role.upper()]
    assert key == derive_role_key(read_key_file(site), found)
    if os.name == "posix":
        assert stat.S_IMODE(out.stat().st_mode) == 0o600
    assert key.hex() not in result.output
    assert read_key_file(site).hex() not in result.output
    assert f"give it only to {role} machines" in result.output


def test_keygen_derives_a_robot_key_bound_to_its_writer_id(tmp_path):
    site, out = tmp_path / "site.key", tmp_path / "robot7.key"
    assert _keygen("--out", str(site)).exit_code == 0
    result = _keygen("--role", "robot", "--writer", "7", "--from", str(site), "--out", str(out))
    assert result.exit_code == 0, result.output
    found = read_writer_key_file(out)
    assert (found.role, found.writer) == (Role.ROBOT, 7)
    assert found.key == derive_robot_key(read_key_file(site), 7)
    assert out.read_text().splitlines()[:2] == ["swarmtag-robot-writer-key-v1", "7"]
    if os.name == "posix":
        assert stat.S_IMODE(out.stat().st_mode) == 0o600
    assert found.key.hex() not in result.output
    assert "robot 7's key" in result.output
    assert "give it only to robot 7's computer" in result.output


@pytest.mark.parametrize(
    ("args", "words"),
    [
        (["--role", "robot"], "--role needs --from"),
        (["--from", "site.key"], "--from needs --role"),
        (["--role", "robot", "--from", "site.key"], "--role robot needs --writer ID"),
        (["--role", "robot", "--writer", "7", "--shared", "--from", "site.key"], "exclude each"),
        (["--role", "operator", "--writer", "7", "--from", "site.key"], "--writer is for robot"),
        (["--role", "operator", "--shared", "--from", "site.key"], "--shared is for robot"),
        (["--writer", "7"], "--writer is for robot keys"),
        (["--role", "robot", "--writer", "65536", "--from", "site.key"], "--writer"),
    ],
)
def test_role_and_from_come_together(tmp_path, args, words):
    result = _keygen(*args, "--out", str(tmp_path / "x.key"))
    assert result.exit_code == 2
    assert words in result.output
    assert not (tmp_path / "x.key").exists()


def test_a_role_key_file_is_no_site_key_to_derive_from(tmp_path):
    site, robot = tmp_path / "site.key", tmp_path / "robot.key"
    assert _keygen("--out", str(site)).exit_code == 0
    assert (
        _keygen(
            "--role", "robot", "--writer", "3", "--from", str(site), "--out", str(robot)
        ).exit_code
        == 0
    )
    result = _keygen("--role", "operator", "--from", str(robot), "--out", str(tmp_path / "o.key"))
    assert result.exit_code == 2
    assert "is a robot key file, not a site key file" in result.output
    assert not (tmp_path / "o.key").exists()


def test_an_unknown_role_is_refused(tmp_path):
    result = _keygen("--role", "admin", "--from", "site.key", "--out", str(tmp_path / "x.key"))
    assert result.exit_code == 2
    assert "admin" in result.output
