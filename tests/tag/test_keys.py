"""Site keys: HKDF (RFC 5869), role keys, and the site key file (issue 11, key handling)."""

from __future__ import annotations

import hashlib
import hmac
import os
import stat
import sys
from pathlib import Path

import pytest

from swarmtag.errors import FieldRangeError, KeyFileError
from swarmtag.tag import (
    ATT_ERRORS,
    SERVICE_UUID,
    STATE_CHAR_UUID,
    WRITE_CHAR_UUID,
    Role,
    derive_role_key,
    generate_site_key,
    read_key_file,
    write_key_file,
)
from swarmtag.tag import keys as keys_module
from swarmtag.tag.keys import (
    HKDF_SALT,
    KEY_FILE_HEADER,
    ROBOT_KEY_FILE_HEADER,
    ROLE_KEY_FILE_HEADERS,
    ROLE_KEY_INFO,
    SITE_KEY_LENGTH,
    hkdf_sha256,
    read_role_key_file,
    write_role_key_file,
)
from tests.tag import test_write as vectors
from tests.tag.test_write import RFC_5869_CASES

KEY = bytes(range(100, 132))
posix_only = pytest.mark.skipif(os.name != "posix", reason="POSIX file modes")


# --- derivation ------------------------------------------------------------------------------


@pytest.mark.parametrize(("ikm", "salt", "info", "length", "okm"), RFC_5869_CASES)
def test_hkdf_matches_rfc_5869(ikm, salt, info, length, okm):
    assert hkdf_sha256(ikm, salt=salt, info=info, length=length).hex() == okm


def test_derivation_parameters_are_the_documented_ones():
    assert HKDF_SALT == b"swarmtag hkdf salt v1"
    assert dict(ROLE_KEY_INFO) == {
        Role.ROBOT: b"swarmtag write key v1 robot",
        Role.OPERATOR: b"swarmtag write key v1 operator",
    }
    for role in Role:
        expected = hkdf_sha256(KEY, salt=HKDF_SALT, info=ROLE_KEY_INFO[role], length=32)
        assert derive_role_key(KEY, role) == expected


@pytest.mark.parametrize(
    ("args", "words"),
    [
        ((b"short", Role.ROBOT), "site_key: must be at least 16 bytes"),
        (("a text site key of 16+", Role.ROBOT), "site_key: .*got str"),
        ((KEY, 3), "role: 3"),
        ((KEY, "robot"), "role: 'robot'"),
    ],
)
def test_derive_role_key_refuses_bad_arguments(args, words):
    with pytest.raises(FieldRangeError, match=words):
        derive_role_key(*args)


@pytest.mark.parametrize("length", [0, -1, 255 * 32 + 1, 1.5])
def test_hkdf_refuses_impossible_lengths(length):
    with pytest.raises(FieldRangeError, match="length"):
        hkdf_sha256(KEY, salt=b"", info=b"", length=length)


def test_generated_keys_are_32_random_bytes():
    keys = {generate_site_key() for _ in range(8)}
    assert len(keys) == 8
    assert {len(key) for key in keys} == {SITE_KEY_LENGTH} == {32}


# --- the key file ----------------------------------------------------------------------------


def test_key_file_round_trip_format_and_mode(tmp_path):
    path = write_key_file(tmp_path / "site.key", KEY)
    assert path == tmp_path / "site.key"
    assert path.read_bytes() == f"{KEY_FILE_HEADER}\n{KEY.hex()}\n".encode()
    assert path.read_text().splitlines()[0] == "swarmtag-site-key-v1"
    if os.name == "posix":
        assert stat.S_IMODE(path.stat().st_mode) == 0o600
    assert read_key_file(path) == KEY
    assert read_key_file(str(path)) == KEY
    assert [p.name for p in tmp_path.iterdir()] == ["site.key"]  # no temporary left


@posix_only
def test_key_file_mode_is_0600_whatever_the_umask(tmp_path):
    old = os.umask(0o000)
    try:
        path = write_key_file(tmp_path / "site.key", KEY)
    finally:
        os.umask(old)
    assert stat.S_IMODE(path.stat().st_mode) == 0o600


def test_existing_file_is_never_overwritten(tmp_path):
    path = tmp_path / "site.key"
    path.write_bytes(b"precious")
    with pytest.raises(KeyFileError, match="already exists; refusing to overwrite"):
        write_key_file(path, KEY)
    assert path.read_bytes() == b"precious"
    link = tmp_path / "dangling.key"
    link.symlink_to(tmp_path / "nowhere")
    with pytest.raises(KeyFileError, match="already exists"):
        write_key_file(link, KEY)
    assert not (tmp_path / "nowhere").exists()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["dangling.key", "site.key"]


def test_a_file_created_meanwhile_is_not_overwritten(tmp_path, monkeypatch):
    """The race between the existence check and the link: the link refuses, too."""
    path = tmp_path / "site.key"
    real_link = os.link

    def racing_link(source, target):
        path.write_bytes(b"someone else's")
        real_link(source, target)

    monkeypatch.setattr(keys_module.os, "link", racing_link)
    with pytest.raises(KeyFileError, match="already exists"):
        write_key_file(path, KEY)
    assert path.read_bytes() == b"someone else's"
    assert [p.name for p in tmp_path.iterdir()] == ["site.key"]


def test_missing_folder_is_refused(tmp_path):
    with pytest.raises(KeyFileError, match=r"folder .*missing.* does not exist"):
        write_key_file(tmp_path / "missing" / "site.key", KEY)
    assert not (tmp_path / "missing").exists()


def test_a_failed_write_leaves_nothing_behind(tmp_path, monkeypatch):
    def full_disk(_fd):
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(keys_module.os, "fsync", full_disk)
    with pytest.raises(KeyFileError, match=r"cannot write key file .*No space left"):
        write_key_file(tmp_path / "site.key", KEY)
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize(
    ("key", "words"), [(b"x" * 16, "32-byte key, got 16"), ("0" * 64, "key: .*got str")]
)
def test_write_refuses_keys_the_format_cannot_hold(tmp_path, key, words):
    with pytest.raises(FieldRangeError, match=words):
        write_key_file(tmp_path / "site.key", key)
    assert list(tmp_path.iterdir()) == []


@posix_only
@pytest.mark.parametrize("mode", [0o640, 0o604, 0o644, 0o660, 0o606, 0o610, 0o601, 0o666])
def test_key_readable_or_writable_by_others_is_refused(tmp_path, mode):
    path = write_key_file(tmp_path / "site.key", KEY)
    path.chmod(mode)
    with pytest.raises(KeyFileError) as caught:
        read_key_file(path)
    message = str(caught.value)
    assert f"(mode {mode:04o})" in message
    assert f"chmod 600 {path}" in message
    assert KEY.hex() not in message


@posix_only
@pytest.mark.parametrize("mode", [0o600, 0o400])
def test_private_modes_are_accepted(tmp_path, mode):
    path = write_key_file(tmp_path / "site.key", KEY)
    path.chmod(mode)
    assert read_key_file(path) == KEY


def _private(path, data: bytes):
    path.write_bytes(data)
    path.chmod(0o600)
    return path


GOOD = f"{KEY_FILE_HEADER}\n{KEY.hex()}\n".encode()


@pytest.mark.parametrize(
    "data",
    [
        b"",
        KEY.hex().encode() + b"\n",  # no header
        GOOD.replace(b"v1", b"v2"),
        GOOD.rstrip(b"\n"),  # no final line feed
        GOOD + b"\n",
        GOOD + b"another line\n",
        GOOD.replace(b"\n", b"\r\n"),
        f"{KEY_FILE_HEADER}\n{KEY.hex()[:-2]}\n".encode(),  # 31 bytes
        f"{KEY_FILE_HEADER}\n{KEY.hex()}00\n".encode(),  # 33 bytes
        f"{KEY_FILE_HEADER}\n{KEY.hex()[:-1]}g\n".encode(),
        f"{KEY_FILE_HEADER}\n {KEY.hex()[1:]}\n".encode(),
        f"{KEY_FILE_HEADER}\n{KEY.hex()[:-1]}é\n".encode(),
        b"\xff" * 100,
        GOOD * 100,  # larger than any key file
    ],
    ids=lambda data: repr(data[:12]),
)
def test_bad_content_is_one_clear_message_without_the_content(tmp_path, data):
    path = _private(tmp_path / "site.key", data)
    with pytest.raises(KeyFileError) as caught:
        read_key_file(path)
    message = str(caught.value)
    assert message == (
        f"key file {path} is not a swarmtag site key file: expected the line "
        "'swarmtag-site-key-v1', then a line of 64 hex digits "
        "(make one with 'swarmtag tag keygen --out FILE')"
    )
    assert KEY.hex()[:16] not in message


def test_upper_case_hex_is_read(tmp_path):
    path = _private(tmp_path / "site.key", f"{KEY_FILE_HEADER}\n{KEY.hex().upper()}\n".encode())
    assert read_key_file(path) == KEY


def test_missing_file_folder_and_special_files_are_refused(tmp_path):
    with pytest.raises(KeyFileError, match="does not exist"):
        read_key_file(tmp_path / "nope.key")
    with pytest.raises(KeyFileError, match="not a regular file"):
        read_key_file(tmp_path)
    if hasattr(os, "mkfifo"):
        fifo = tmp_path / "fifo.key"
        os.mkfifo(fifo, 0o600)
        with pytest.raises(KeyFileError, match="not a regular file"):
            read_key_file(fifo)  # must not block waiting for a writer


@pytest.mark.skipif(
    os.name != "posix" or os.geteuid() == 0, reason="root reads files whatever their mode"
)
def test_unreadable_file_is_a_key_file_error(tmp_path):
    path = write_key_file(tmp_path / "site.key", KEY)
    path.chmod(0o000)
    with pytest.raises(KeyFileError, match=r"cannot open key file .*ermission"):
        read_key_file(path)


@pytest.mark.parametrize("bad", [None, 3, b"site.key", "", "site\0.key"])
def test_bad_paths_are_refused(bad):
    for call in (lambda: read_key_file(bad), lambda: write_key_file(bad, KEY)):
        with pytest.raises(KeyFileError, match="key file path"):
            call()


def test_symlink_to_a_private_key_file_is_followed(tmp_path):
    path = write_key_file(tmp_path / "site.key", KEY)
    link = tmp_path / "current.key"
    link.symlink_to(path)
    assert read_key_file(link) == KEY


@pytest.mark.skipif(sys.platform == "win32", reason="POSIX hard links")
def test_filesystems_without_hard_links_get_a_clear_error(tmp_path, monkeypatch):
    def no_links(_source, _target):
        raise OSError(1, "Operation not permitted")

    monkeypatch.setattr(keys_module.os, "link", no_links)
    with pytest.raises(KeyFileError, match=r"cannot write key file .*Operation not permitted"):
        write_key_file(tmp_path / "site.key", KEY)
    assert list(tmp_path.iterdir()) == []


def test_names_too_long_for_the_system_are_key_file_errors(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    for path in ("x" * 300, "x" * 300 + "/site.key", str(tmp_path / ("y" * 300))):
        with pytest.raises(KeyFileError, match=r"(too long|does not exist)"):
            write_key_file(path, KEY)
        with pytest.raises(KeyFileError, match=r"(too long|does not exist)"):
            read_key_file(path)
    assert list(tmp_path.iterdir()) == []


# --- role key files ---------------------------------------------------------------------------


def test_role_key_file_headers_are_the_documented_ones():
    assert dict(ROLE_KEY_FILE_HEADERS) == {
        Role.ROBOT: "swarmtag-robot-key-v1",
        Role.OPERATOR: "swarmtag-operator-key-v1",
    }


@pytest.mark.parametrize("role", list(Role))
def test_role_key_file_round_trip_format_and_mode(tmp_path, role):
    key = derive_role_key(KEY, role)
    path = write_role_key_file(tmp_path / "role.key", role, key)
    header = ROLE_KEY_FILE_HEADERS[role]
    assert path.read_bytes() == f"{header}\n{key.hex()}\n".encode()
    if os.name == "posix":
        assert stat.S_IMODE(path.stat().st_mode) == 0o600
    found, read = read_role_key_file(path)
    assert found is role
    assert read == key == derive_role_key(KEY, role)
    assert [p.name for p in tmp_path.iterdir()] == ["role.key"]


def test_the_site_key_file_is_refused_where_a_role_key_is_expected(tmp_path):
    site = write_key_file(tmp_path / "site.key", KEY)
    with pytest.raises(KeyFileError) as caught:
        read_role_key_file(site)
    assert str(caught.value) == (
        f"key file {site} is the site key file, not a writer's key file: a writer holds only its "
        f"own key; derive one with 'swarmtag tag keygen --role robot --writer ID --from {site} "
        "--out FILE' (or --role operator)"
    )


@pytest.mark.parametrize("role", list(Role))
def test_a_role_key_file_is_refused_where_the_site_key_is_expected(tmp_path, role):
    path = write_role_key_file(tmp_path / "role.key", role, derive_role_key(KEY, role))
    with pytest.raises(KeyFileError) as caught:
        read_key_file(path)
    message = str(caught.value)
    assert message.startswith(
        f"key file {path} is a {role.name.lower()} key file, not a site key file"
    )
    assert "'swarmtag tag keygen --out FILE'" in message
    assert derive_role_key(KEY, role).hex() not in message


ROBOT_GOOD = f"swarmtag-robot-key-v1\n{KEY.hex()}\n".encode()


@pytest.mark.parametrize(
    "data",
    [
        b"",
        ROBOT_GOOD.replace(b"robot", b"admin"),
        ROBOT_GOOD.replace(b"v1", b"v2"),
        ROBOT_GOOD.rstrip(b"\n"),
        ROBOT_GOOD + b"x\n",
        ROBOT_GOOD.replace(b"\n", b"\r\n"),
        f"swarmtag-operator-key-v1\n{KEY.hex()[:-2]}\n".encode(),
        f"swarmtag-robot-key-v1\n{KEY.hex()}0\n".encode(),
        f"swarmtag-robot-key-v1\n{KEY.hex()[:-1]}z\n".encode(),
        b"\xff" * 90,
    ],
    ids=lambda data: repr(data[:12]),
)
def test_bad_role_key_content_is_one_message_without_the_content(tmp_path, data):
    path = _private(tmp_path / "role.key", data)
    with pytest.raises(KeyFileError) as caught:
        read_role_key_file(path)
    message = str(caught.value)
    assert message == (
        f"key file {path} is not a swarmtag writer's key file: expected the line "
        "'swarmtag-robot-writer-key-v1', a writer id and 64 hex digits, or "
        "'swarmtag-operator-key-v1' (or 'swarmtag-robot-key-v1') and 64 hex digits (derive one "
        "with 'swarmtag tag keygen --role robot --writer ID --from SITE.key --out FILE' or "
        "'--role operator --from SITE.key --out FILE')"
    )
    assert KEY.hex()[:16] not in message


@posix_only
@pytest.mark.parametrize("mode", [0o640, 0o604, 0o644])
def test_role_key_readable_by_others_is_refused(tmp_path, mode):
    key = derive_role_key(KEY, Role.ROBOT)
    path = write_role_key_file(tmp_path / "robot.key", Role.ROBOT, key)
    path.chmod(mode)
    with pytest.raises(KeyFileError) as caught:
        read_role_key_file(path)
    assert f"(mode {mode:04o})" in str(caught.value)
    assert f"chmod 600 {path}" in str(caught.value)
    assert key.hex() not in str(caught.value)


def test_role_key_files_are_never_overwritten_and_refuse_bad_arguments(tmp_path):
    path = write_role_key_file(tmp_path / "robot.key", Role.ROBOT, derive_role_key(KEY, Role.ROBOT))
    before = path.read_bytes()
    with pytest.raises(KeyFileError, match="already exists; refusing to overwrite"):
        write_role_key_file(path, Role.OPERATOR, derive_role_key(KEY, Role.OPERATOR))
    assert path.read_bytes() == before
    with pytest.raises(FieldRangeError, match="role: 3"):
        write_role_key_file(tmp_path / "x.key", 3, KEY)
    with pytest.raises(FieldRangeError, match="32-byte key, got 16"):
        write_role_key_file(tmp_path / "x.key", Role.ROBOT, KEY[:16])
    with pytest.raises(KeyFileError, match="does not exist"):
        read_role_key_file(tmp_path / "missing.key")
    assert [p.name for p in tmp_path.iterdir()] == ["robot.key"]


# --- docs/hardware.md states what the firmware needs, as the code has it ---------------------


def test_hardware_doc_states_the_derivation_uuids_codes_and_vectors():
    text = (Path(__file__).parents[2] / "docs" / "hardware.md").read_text(encoding="utf-8")
    prk = hmac.new(vectors.SALT, vectors.KEY, hashlib.sha256).hexdigest()  # RFC 5869 extract
    for value in (
        SERVICE_UUID,
        WRITE_CHAR_UUID,
        STATE_CHAR_UUID,
        HKDF_SALT.decode(),
        HKDF_SALT.hex(),
        *(info.decode() for info in ROLE_KEY_INFO.values()),
        *(info.hex() for info in ROLE_KEY_INFO.values()),
        vectors.KEY.hex(),
        prk,
        vectors.ROBOT_KEY.hex(),
        vectors.ROBOT7_KEY.hex(),
        vectors.ROBOT_INFO.decode(),
        vectors.ROBOT_INFO.hex(),
        vectors.OPERATOR_KEY.hex(),
        f"`{vectors.ROBOT_LIFT[:12].hex()}` `{vectors.ROBOT_LIFT[12:].hex()}`",
        f"`{vectors.LEGACY_ROBOT_LIFT[:12].hex()}` `{vectors.LEGACY_ROBOT_LIFT[12:].hex()}`",
        ROBOT_KEY_FILE_HEADER,
        f"`{vectors.OPERATOR_WRITE[:12].hex()}` `{vectors.OPERATOR_WRITE[12:].hex()}`",
        KEY_FILE_HEADER,
        *ROLE_KEY_FILE_HEADERS.values(),
    ):
        assert value in text, value
    for error, code in ATT_ERRORS.items():
        row = next(line for line in text.splitlines() if f"`{error.__name__}`" in line)
        assert f"`0x{code:02X}`" in row, row
