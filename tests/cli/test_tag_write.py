"""``swarmtag tag write`` end to end without a radio: the hidden loopback tag, exit 0 / 1 / 2."""

from __future__ import annotations

import json

import pytest

pytest.importorskip("bleak")

from swarmtag.cli import main, tag_write
from swarmtag.tag import (
    FileStore,
    Role,
    TagModel,
    TagState,
    TagStatus,
    derive_robot_key,
    derive_role_key,
    generate_site_key,
    read_key_file,
    write_key_file,
    write_robot_key_file,
    write_role_key_file,
)
from swarmtag.tag.counter import CounterFile

ADDRESS = "AA:BB:CC:DD:EE:01"
WAITING = TagState(urgency=5, status=TagStatus.AWAITING_PICKUP, destination=2, marker=12)


@pytest.fixture
def bench(tmp_path, monkeypatch):
    """A site key, robot 7's key, the operator key, the legacy shared robot key (shared.key),
    and a software tag (marker 12) in a FileStore file."""
    monkeypatch.chdir(tmp_path)
    site = write_key_file(tmp_path / "site.key", generate_site_key())
    site_key = read_key_file(site)
    write_robot_key_file(tmp_path / "robot.key", 7, derive_robot_key(site_key, 7))
    operator = derive_role_key(site_key, Role.OPERATOR)
    write_role_key_file(tmp_path / "operator.key", Role.OPERATOR, operator)
    shared = derive_role_key(site_key, Role.ROBOT)
    write_role_key_file(tmp_path / "shared.key", Role.ROBOT, shared)
    TagModel.provision(WAITING, site_key=site_key, store=FileStore("tag.state"))
    return tmp_path


LOOPBACK = ("--backend", "loopback", "--loopback-state", "tag.state", "--loopback-key", "site.key")


def run(capsys, *argv: str) -> tuple[int, str, str]:
    with pytest.raises(SystemExit) as exited:
        main(["tag", "write", *argv])
    out, err = capsys.readouterr()
    return int(exited.value.code or 0), out, err


def tag_state(bench) -> TagState:
    site = read_key_file(bench / "site.key")
    return TagModel.boot(site_key=site, store=FileStore(bench / "tag.state")).state


def test_a_robot_lifts_and_the_counter_is_saved_next_to_its_key(capsys, bench):
    code, out, err = run(
        capsys, ADDRESS.lower(), "--key-file", "robot.key", "--writer", "7", "--role", "robot",
        "--status", "picked_up", *LOOPBACK,
    )  # fmt: skip
    assert (code, err) == (0, "")
    assert out == (
        f"accepted by tag 12 at {ADDRESS}: writer 7 (robot), counter 0 "
        "(saved in robot.key.counters)\n"
        "now: urgency 5, status PICKED_UP, destination 2, marker 12\n"
    )
    assert tag_state(bench).status is TagStatus.PICKED_UP
    assert CounterFile(bench / "robot.key.counters").last(7) == 0
    assert tag_write.counter_file_for(bench / "robot.key") == bench / "robot.key.counters"


def test_an_operator_write_as_json(capsys, bench):
    code, out, _err = run(
        capsys, ADDRESS, "--key-file", "operator.key", "--writer", "2", "--urgency", "9",
        "--destination", "4", "--counter-file", "op.counters", "--json", *LOOPBACK,
    )  # fmt: skip
    assert code == 0
    assert json.loads(out) == {
        "accepted": True,
        "address": ADDRESS,
        "writer": 2,
        "role": "operator",
        "counter": 0,
        "counter_file": "op.counters",
        "before": {"urgency": 5, "status": "AWAITING_PICKUP", "destination": 2, "marker": 12},
        "after": {"urgency": 9, "status": "AWAITING_PICKUP", "destination": 4, "marker": 12},
        "confirmed": True,
    }


def test_a_refused_write_exits_1_with_the_att_code_and_the_tag_unchanged(capsys, bench):
    code, out, err = run(
        capsys, ADDRESS, "--key-file", "robot.key", "--writer", "7", "--urgency", "0", *LOOPBACK
    )
    assert (code, out) == (tag_write.EXIT_REFUSED, "")
    assert err == (
        f"swarmtag: refused: tag 12 at {ADDRESS} refused the write: ATT error 0x83 "
        "(RoleNotAllowed): a robot may only change the status; urgency and destination need "
        "the operator key\n"
    )
    assert tag_state(bench) == WAITING
    assert CounterFile(bench / "robot.key.counters").last(7) == 0  # spent on the refusal


def test_a_refusal_as_json(capsys, bench):
    code, out, err = run(
        capsys, ADDRESS, "--key-file", "robot.key", "--writer", "7", "--status", "idle",
        "--json", *LOOPBACK,
    )  # fmt: skip
    assert code == 1
    body = json.loads(out)
    assert {k: body[k] for k in ("accepted", "att_error", "refusal", "writer", "role")} == {
        "accepted": False,
        "att_error": 0x84,
        "refusal": "IllegalTransition",
        "writer": 7,
        "role": "robot",
    }
    assert err.startswith("swarmtag: refused: ")
    assert err.count("\n") == 1


def test_a_lost_counter_file_is_refused_as_a_replay_and_a_restart_is_not(capsys, bench):
    lift = (ADDRESS, "--key-file", "robot.key", "--writer", "7", *LOOPBACK)
    assert run(capsys, *lift, "--status", "picked_up")[0] == 0
    code, _out, err = run(capsys, *lift, "--status", "idle", "--counter-file", "new.counters")
    assert code == 1
    assert "ATT error 0x81 (ReplayedWrite)" in err
    assert tag_state(bench).status is TagStatus.PICKED_UP
    assert run(capsys, *lift, "--status", "idle")[0] == 0  # its own file: counter 1, accepted
    assert tag_state(bench).status is TagStatus.IDLE


def test_a_robot_key_file_names_its_writer_and_binds_the_release(capsys, bench):
    """Robot 7 writes without --writer; robot 9 cannot release what robot 7 lifted (issue 35)."""
    site = read_key_file(bench / "site.key")
    write_robot_key_file(bench / "robot9.key", 9, derive_robot_key(site, 9))
    code, out, _err = run(capsys, ADDRESS, "--key-file", "robot.key", "--status", "picked_up",
                          *LOOPBACK)  # fmt: skip
    assert code == 0
    assert "writer 7 (robot), counter 0" in out
    code, out, err = run(capsys, ADDRESS, "--key-file", "robot9.key", "--status", "idle",
                         *LOOPBACK)  # fmt: skip
    assert (code, out) == (1, "")
    assert err.startswith(
        f"swarmtag: refused: tag 12 at {ADDRESS} refused the write: ATT error 0x84 "
        "(IllegalTransition): a robot may only lift (AWAITING_PICKUP -> PICKED_UP) or release "
        "(PICKED_UP -> IDLE) a carrier it lifted itself (the tag was PICKED_UP)"
    )
    assert tag_state(bench).status is TagStatus.PICKED_UP
    code, _out, _err = run(capsys, ADDRESS, "--key-file", "operator.key", "--writer", "1000",
                           "--status", "idle", *LOOPBACK)  # fmt: skip
    assert code == 0  # an operator overrides
    assert tag_state(bench).status is TagStatus.IDLE


def test_the_shared_robot_key_is_refused_by_a_new_tag(capsys, bench):
    code, _out, err = run(capsys, ADDRESS, "--key-file", "shared.key", "--writer", "7",
                          "--status", "picked_up", *LOOPBACK)  # fmt: skip
    assert code == 1
    assert "ATT error 0x80 (ForgedWrite)" in err
    assert "the shared robot key only on tags set to accept it" in err
    assert tag_state(bench) == WAITING


def test_a_write_reads_the_counter_file_once(capsys, bench, monkeypatch):
    """A full table (65,536 writers) is read and parsed once per write (issue 35)."""
    from swarmtag.tag import counter as counter_module
    from swarmtag.tag.counter import format_counters, parse_counters

    (bench / "robot.key.counters").write_bytes(format_counters(dict.fromkeys(range(65536), 3)))
    parsed: list[int] = []
    monkeypatch.setattr(
        counter_module, "parse_counters", lambda d: parsed.append(1) or parse_counters(d)
    )
    monkeypatch.setattr(counter_module, "_SETTLED_NS", 0)  # the file above counts as settled
    code, out, _err = run(capsys, ADDRESS, "--key-file", "robot.key", "--status", "picked_up",
                          *LOOPBACK)  # fmt: skip
    assert code == 0
    assert "counter 4" in out
    assert parsed == [1]
    assert CounterFile(bench / "robot.key.counters").check() == {
        **dict.fromkeys(range(65536), 3),
        7: 4,
    }


@pytest.mark.parametrize(
    ("argv", "words"),
    [
        (("--key-file", "site.key", "--writer", "1", "--urgency", "3"), "is the site key file"),
        (("--key-file", "robot.key", "--writer", "7", "--role", "operator", "--urgency", "3"),
         "--role operator does not match the key file robot.key, which holds the robot key"),
        (("--key-file", "robot.key", "--writer", "9", "--status", "idle"),
         "writer 9 does not match the key file robot.key, which is robot 7's key"),
        (("--key-file", "operator.key", "--urgency", "3"),
         "holds the operator key, shared by its writers: give this writer's id (--writer ID)"),
        (("--key-file", "shared.key", "--status", "idle"),
         "holds the robot key, shared by its writers: give this writer's id (--writer ID)"),
        (("--key-file", "robot.key", "--writer", "7"), "give at least one of --urgency"),
        (("--key-file", "robot.key", "--writer", "7", "--status", "idle", "--marker", "3"),
         "is marker 12, not 3: nothing was sent"),
        (("--key-file", "robot.key", "--writer", "7", "--status", "idle", "--counter-file",
          "site.key"), "is not a swarmtag counter file"),
        (("--key-file", "robot.key", "--writer", "7", "--status", "idle", "--counter-file",
          "missing/c"), "does not exist"),
        (("--key-file", "robot.key", "--writer", "70000", "--status", "idle"), "--writer"),
        (("--key-file", "robot.key", "--writer", "7", "--status", "lifted"), "--status"),
        (("--key-file", "robot.key", "--writer", "7", "--status", "idle", "--timeout", "nan"),
         "--timeout"),
        (("--key-file", "robot.key", "--writer", "7", "--status", "idle", "--adapter", "eth0"),
         "not a BlueZ adapter name"),
    ],
)  # fmt: skip
def test_bad_input_is_one_line_exit_2_and_nothing_is_sent(capsys, bench, argv, words):
    before = sorted(p.name for p in bench.iterdir())
    code, out, err = run(capsys, ADDRESS, *argv, *LOOPBACK)
    assert (code, out) == (2, "")
    assert err.startswith("swarmtag: error: ")
    assert err.count("\n") == 1
    assert words in err
    assert tag_state(bench) == WAITING
    assert sorted(p.name for p in bench.iterdir()) == before


def test_a_bad_address_is_refused(capsys, bench):
    code, _out, err = run(capsys, "12", "--key-file", "robot.key", "--writer", "7",
                          "--status", "idle", *LOOPBACK)  # fmt: skip
    assert code == 2
    assert "is not a Bluetooth address such as AA:BB:CC:DD:EE:FF" in err


def test_loopback_needs_its_tag(capsys, bench):
    code, _out, err = run(capsys, ADDRESS, "--key-file", "robot.key", "--writer", "7",
                          "--status", "idle", "--backend", "loopback")  # fmt: skip
    assert code == 2
    assert "--backend loopback needs --loopback-state and --loopback-key" in err


@pytest.mark.parametrize(
    ("state", "words"),
    [("missing.state", "no such software tag state file"), ("fifo", "not a regular file")],
)
def test_a_loopback_tag_that_is_no_file_is_refused_without_hanging(capsys, bench, state, words):
    import os

    os.mkfifo(bench / "fifo")
    code, _out, err = run(capsys, ADDRESS, "--key-file", "robot.key", "--writer", "7",
                          "--status", "idle", "--backend", "loopback", "--loopback-state", state,
                          "--loopback-key", "site.key")  # fmt: skip
    assert code == 2
    assert words in err


def test_no_radio_is_one_line_exit_2_and_spends_no_counter(capsys, bench, monkeypatch):
    """The real bleak path on a machine without BlueZ (or with bleak's errors injected)."""
    from bleak.exc import BleakDBusError

    from swarmtag.tag.backends import bleak_writer

    class NoBlueZ:
        def __init__(self, address, **options):
            self.address = address

        async def connect(self):
            raise BleakDBusError("org.freedesktop.DBus.Error.ServiceUnknown", [])

        async def disconnect(self):
            pass

    monkeypatch.setattr(bleak_writer.bleak, "BleakClient", NoBlueZ)
    code, out, err = run(capsys, ADDRESS, "--key-file", "robot.key", "--writer", "7",
                         "--status", "picked_up", "--adapter", "hci1")  # fmt: skip
    assert (code, out) == (2, "")
    assert err == (
        f"swarmtag: error: could not connect to {ADDRESS}: BlueZ is not reachable (no D-Bus "
        "system bus or bluetoothd): install and start BlueZ (sudo apt install bluez; sudo "
        "systemctl start bluetooth)\n"
    )
    assert not (bench / "robot.key.counters").exists()


def test_a_missing_ble_extra_is_one_line(capsys, bench, monkeypatch):
    import builtins

    real_import = builtins.__import__

    def no_bleak(name, *args, **kwargs):
        if name == "swarmtag.tag.backends.bleak_writer":
            error = ImportError("No module named 'bleak'")
            error.name = "bleak"
            raise error
        return real_import(name, *args, **kwargs)

    monkeypatch.setattr(builtins, "__import__", no_bleak)
    code, _out, err = run(capsys, ADDRESS, "--key-file", "robot.key", "--writer", "7",
                          "--status", "picked_up")  # fmt: skip
    assert code == 2
    assert err == (
        "swarmtag: error: tag write needs the bleak package, which is not installed: "
        "pip install 'swarmtag[ble]'\n"
    )


def test_help_text(capsys):
    with pytest.raises(SystemExit) as exited:
        main(["tag", "write", "--help"])
    out = " ".join(capsys.readouterr().out.split())
    assert exited.value.code == 0
    assert "exits 1 if the tag refuses the write" in out
    assert "--loopback" not in out
    assert "--backend" not in out
