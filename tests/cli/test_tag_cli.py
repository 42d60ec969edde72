"""``swarmtag tag encode|decode`` and the CLI's error boundary (SPEC §8.2)."""

from __future__ import annotations

import json
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from swarmtag.cli import main


def run(capsys, *argv: str) -> tuple[int, str, str]:
    with pytest.raises(SystemExit) as exited:
        main(list(argv))
    out, err = capsys.readouterr()
    return int(exited.value.code or 0), out, err


def test_encode_spec_example(capsys):
    code, out, err = run(
        capsys, "tag", "encode", "--urgency", "7", "--status", "awaiting_pickup",
        "--destination", "3", "--marker", "12",
    )  # fmt: skip
    assert (code, out, err) == (0, "ffff0701030c\n", "")


@pytest.mark.parametrize(
    ("status", "hex_out"),
    [
        ("IDLE", "ffff09000001"),
        ("Picked_Up", "ffff09020001"),
        ("1", "ffff09010001"),
        ("0", "ffff09000001"),
    ],
)
def test_encode_status_names_any_case_or_numbers(capsys, status, hex_out):
    code, out, _ = run(
        capsys,
        "tag",
        "encode",
        "--urgency",
        "9",
        "--status",
        status,
        "--destination",
        "0",
        "--marker",
        "1",
    )
    assert (code, out.strip()) == (0, hex_out)


def test_decode_json_keys(capsys):
    code, out, _ = run(capsys, "tag", "decode", "ffff0701030c", "--json")
    assert code == 0
    assert json.loads(out) == {
        "company_id": 65535,
        "urgency": 7,
        "status": "AWAITING_PICKUP",
        "destination": 3,
        "marker": 12,
    }


def test_decode_readable(capsys):
    code, out, _ = run(capsys, "tag", "decode", "FF:FF:09:02:00:05")
    assert code == 0
    assert out.split() == [
        "company_id", "0xffff", "urgency", "9", "status", "PICKED_UP",
        "destination", "0", "marker", "5",
    ]  # fmt: skip


@pytest.mark.parametrize(
    ("argv", "words"),
    [
        (["tag", "decode", "ffff0a01030c"], "urgency byte is 10"),
        (["tag", "decode", "ffff0705030c"], "status byte is 0x05"),
        (["tag", "decode", "4c000701030c"], "company id is 0x004c"),
        (["tag", "decode", "ffff07"], "3 bytes, expected 6"),
        (["tag", "decode", "zz"], "not a hex byte string"),
        (["tag", "decode", "fff"], "not a hex byte string"),
        (["tag", "decode"], "Missing argument 'HEX'"),
        (["tag", "encode", "--urgency", "10", "--status", "idle", "--destination", "0", "--marker", "0"], "--urgency"),
        (["tag", "encode", "--urgency", "1", "--status", "lost", "--destination", "0", "--marker", "0"], "not a tag status"),
        (["tag", "encode", "--urgency", "1", "--status", "3", "--destination", "0", "--marker", "0"], "not a tag status"),
        (["tag", "encode", "--urgency", "1", "--status", "idle", "--destination", "256", "--marker", "0"], "--destination"),
        (["tag", "encode", "--urgency", "x", "--status", "idle", "--destination", "0", "--marker", "0"], "'x' is not a valid integer"),
        (["tag", "encode", "--urgency", "1"], "Missing option"),
        (["tag", "frobnicate"], "No such command 'frobnicate'"),
        (["--bogus"], "--bogus"),
    ],
)  # fmt: skip
def test_bad_input_one_line_exit_2(capsys, argv, words):
    code, out, err = run(capsys, *argv)
    assert code == 2
    assert out == ""
    assert err.count("\n") == 1, err
    assert err.startswith("swarmtag: error: ")
    assert words in err
    assert "Traceback" not in err


@pytest.mark.parametrize(
    "argv",
    [
        ["--help"],
        ["tag", "--help"],
        ["tag", "encode", "--help"],
        ["tag", "decode", "-h"],
        ["demo", "--help"],
    ],
)
def test_help_everywhere(capsys, argv):
    code, out, _ = run(capsys, *argv)
    assert code == 0
    assert "Usage:" in out


def test_bare_group_prints_help(capsys):
    code, out, _ = run(capsys)
    assert code == 0
    assert "Usage:" in out
    assert "tag" in out


def test_installed_entry_point_end_to_end():
    exe = shutil.which("swarmtag", path=str(Path(sys.executable).parent))
    assert exe is not None, "the swarmtag console script is not installed next to this Python"
    good = subprocess.run(
        [exe, "tag", "decode", "ffff0701030c", "--json"],
        capture_output=True,
        text=True,
        check=False,
    )
    assert good.returncode == 0
    assert json.loads(good.stdout)["status"] == "AWAITING_PICKUP"
    bad = subprocess.run(
        [exe, "tag", "decode", "ffff"], capture_output=True, text=True, check=False
    )
    assert (bad.returncode, bad.stdout) == (2, "")
    assert bad.stderr == "swarmtag: error: payload has 2 bytes, expected 6\n"
