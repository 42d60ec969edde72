"""``swarmtag tag emulate``: replayed writes, the state file, the E-ink file, radio failures."""

from __future__ import annotations

import os
import threading
import time
from pathlib import Path

import pytest

from swarmtag.cli import main, tag_emulate
from swarmtag.errors import RadioError
from swarmtag.tag import (
    Change,
    FileStore,
    Role,
    TagState,
    TagStatus,
    WriteSigner,
    derive_robot_key,
    derive_role_key,
    write_key_file,
)
from swarmtag.tag.backends.server import ReplayTagServer
from swarmtag.tag.emulator import SoftwareTag

SITE_KEY = bytes(range(100, 132))
OPERATOR = derive_role_key(SITE_KEY, Role.OPERATOR)
ROBOT = derive_robot_key(SITE_KEY, 7)  # robot 7's own key
SHARED_ROBOT = derive_role_key(SITE_KEY, Role.ROBOT)  # the legacy key of all robots


def run(capsys, *argv: str) -> tuple[int, str, str]:
    with pytest.raises(SystemExit) as exited:
        main(["tag", "emulate", *argv])
    out, err = capsys.readouterr()
    return int(exited.value.code or 0), out, err


@pytest.fixture
def work(tmp_path, monkeypatch) -> Path:
    monkeypatch.chdir(tmp_path)
    write_key_file(tmp_path / "site.key", SITE_KEY)
    return tmp_path


def replay_file(path: Path, *writes: bytes, comment: bool = True) -> Path:
    lines = ["# written by the test"] if comment else []
    path.write_text("\n".join([*lines, *(w.hex() for w in writes), ""]))
    return path


def bench_writes() -> list[bytes]:
    operator = WriteSigner(writer=1, role=Role.OPERATOR, key=OPERATOR)
    robot = WriteSigner(writer=7, role=Role.ROBOT, key=ROBOT)
    ready = operator.sign(12, Change(urgency=8, status=TagStatus.AWAITING_PICKUP, destination=3))
    lift = robot.sign(12, Change(status=TagStatus.PICKED_UP))
    return [ready, lift, lift]


def test_replayed_writes_print_one_line_each_and_persist(capsys, work):
    replay_file(work / "writes.txt", *bench_writes())
    code, out, err = run(
        capsys, "--marker", "12", "--key-file", "site.key", "--state-file", "tag.bin",
        "--replay", "writes.txt", "--eink", "tag.png",
    )  # fmt: skip
    assert (code, err) == (0, "")
    assert out.splitlines() == [
        "software tag 12 (provisioned in tag.bin) on replay: urgency 0, IDLE, destination 0",
        (
            "accepted from writer 1 (operator, counter 0): now urgency 8, AWAITING_PICKUP, "
            "destination 3"
        ),
        "accepted from writer 7 (robot, counter 0): now urgency 8, PICKED_UP, destination 3",
        (
            "refused from writer 7 (robot, counter 0): ReplayedWrite (ATT 0x81): counter 0 from "
            "writer 7 is not above the highest seen (0): replay refused"
        ),
        "served 3 writes: 2 accepted, 1 refused (ReplayedWrite 1)",
    ]
    final = TagState(urgency=8, status=TagStatus.PICKED_UP, destination=3, marker=12)
    assert SoftwareTag.boot(site_key=SITE_KEY, store=FileStore(work / "tag.bin")).state == final
    pytest.importorskip("PIL")
    from swarmtag.tag.eink import png_bytes

    assert (work / "tag.png").read_bytes() == png_bytes(final)


def test_a_second_run_boots_the_state_file_and_remembers_the_counters(capsys, work):
    replay_file(work / "writes.txt", *bench_writes())
    argv = ("--marker", "12", "--key-file", "site.key", "--state-file", "tag.bin")
    assert run(capsys, *argv, "--replay", "writes.txt")[0] == 0
    code, out, _err = run(capsys, *argv, "--replay", "writes.txt")
    assert code == 0
    assert out.splitlines()[0] == (
        "software tag 12 (booted in tag.bin) on replay: urgency 8, PICKED_UP, destination 3"
    )
    assert out.splitlines()[-1] == "served 3 writes: 0 accepted, 3 refused (ReplayedWrite 3)"


def test_without_a_state_file_the_tag_lives_in_memory(capsys, work):
    replay_file(work / "writes.txt", *bench_writes()[:1])
    code, out, _err = run(
        capsys, "--marker", "12", "--key-file", "site.key", "--replay", "writes.txt",
        "--urgency", "5", "--status", "AWAITING_PICKUP", "--destination", "2",
    )  # fmt: skip
    assert code == 0
    assert out.splitlines()[0] == (
        "software tag 12 (provisioned in memory) on replay: urgency 5, AWAITING_PICKUP, "
        "destination 2"
    )
    assert sorted(p.name for p in work.iterdir()) == ["site.key", "writes.txt"]


def test_another_marker_or_new_fields_for_a_stored_tag_are_refused(capsys, work):
    replay_file(work / "none.txt")
    argv = ("--key-file", "site.key", "--state-file", "tag.bin", "--replay", "none.txt")
    assert run(capsys, "--marker", "12", *argv)[0] == 0
    before = (work / "tag.bin").read_bytes()
    code, out, err = run(capsys, "--marker", "13", *argv)
    assert (code, out) == (2, "")
    assert err == (
        "swarmtag: error: --state-file tag.bin: marker: 13 is not the stored tag's marker (12); "
        "use marker 12, or another state file for tag 13\n"
    )
    code, _out, err = run(capsys, "--marker", "12", "--urgency", "3", *argv)
    assert code == 2
    assert "urgency: only set up a new tag" in err
    assert (work / "tag.bin").read_bytes() == before


def test_no_bluez_is_one_line_exit_2_and_leaves_no_state_file(capsys, work, monkeypatch):
    pytest.importorskip("bless")
    monkeypatch.setenv("DBUS_SYSTEM_BUS_ADDRESS", f"unix:path={work / 'no-bus'}")
    code, out, err = run(
        capsys, "--marker", "3", "--key-file", "site.key", "--state-file", "tag.bin",
        "--eink", "tag.png", "--timeout", "5",
    )  # fmt: skip
    assert (code, out) == (2, "")
    assert err == (
        "swarmtag: error: BlueZ is not reachable (no D-Bus system bus or bluetoothd): install "
        "and start BlueZ (sudo apt install bluez; sudo systemctl start bluetooth)\n"
    )
    assert sorted(p.name for p in work.iterdir()) == ["site.key"]


def test_a_stored_tag_keeps_its_file_when_the_radio_fails(capsys, work, monkeypatch):
    replay_file(work / "none.txt")
    argv = ("--marker", "3", "--key-file", "site.key", "--state-file", "tag.bin")
    assert run(capsys, *argv, "--replay", "none.txt")[0] == 0

    class NoRadio(ReplayTagServer):
        def start(self) -> None:
            self._failure = RadioError("no Bluetooth adapter found: plug in a BLE adapter")

    monkeypatch.setattr(
        tag_emulate, "_open_server", lambda tag, _replay, _adapter: NoRadio(tag, [])
    )
    code, _out, err = run(capsys, *argv)
    assert code == 2
    assert err == "swarmtag: error: no Bluetooth adapter found: plug in a BLE adapter\n"
    assert (work / "tag.bin").exists()


class Interrupted(ReplayTagServer):
    """Serves its writes, then Ctrl-C arrives while the command waits for more."""

    def poll(self) -> None:
        super().poll()
        raise KeyboardInterrupt

    @property
    def finished(self) -> bool:
        return False


def test_ctrl_c_reports_what_was_served_then_exits_130(capsys, work, monkeypatch):
    writes = bench_writes()[:1]
    servers: list[Interrupted] = []

    def open_server(tag, _replay, _adapter):
        servers.append(Interrupted(tag, writes))
        return servers[-1]

    monkeypatch.setattr(tag_emulate, "_open_server", open_server)
    code, out, err = run(capsys, "--marker", "12", "--key-file", "site.key", "--state-file", "t")
    assert code == 130
    assert out.splitlines()[1].startswith("accepted from writer 1 (operator, counter 0)")
    assert out.splitlines()[-1] == "served 1 writes: 1 accepted, 0 refused"
    assert err.startswith("swarmtag: error: aborted; software tag stopped by Ctrl-C; its state")
    assert not servers[0]._running  # stopped


def test_a_store_failure_while_serving_is_exit_2(capsys, work, monkeypatch):
    replay_file(work / "writes.txt", *bench_writes())

    def no_space(self, record: bytes) -> None:
        if self.path.exists():
            raise OSError(28, "No space left on device")
        self.path.write_bytes(record)

    monkeypatch.setattr(FileStore, "save", no_space)
    code, out, err = run(
        capsys, "--marker", "12", "--key-file", "site.key", "--state-file", "tag.bin",
        "--replay", "writes.txt",
    )  # fmt: skip
    assert code == 2
    assert out.splitlines()[-1] == "served 0 writes: 0 accepted, 0 refused"
    assert err == (
        "swarmtag: error: the tag's state could not be saved, so it stopped serving: "
        "No space left on device\n"
    )


@pytest.mark.parametrize(
    ("text", "says"),
    [
        ("0102\nzz\n", "--replay writes.txt: line 2 is not a hex byte string: 'zz'"),
        ("abc\n", "line 1 is not a hex byte string"),
        ("0x\n", "line 1 is not a hex byte string"),
    ],
)
def test_a_bad_replay_file_is_refused_before_anything_is_saved(capsys, work, text, says):
    (work / "writes.txt").write_text(text)
    code, out, err = run(
        capsys, "--marker", "1", "--key-file", "site.key", "--state-file", "tag.bin",
        "--replay", "writes.txt",
    )  # fmt: skip
    assert (code, out) == (2, "")
    assert says in err
    assert err.count("\n") == 1
    assert not (work / "tag.bin").exists()


def test_replay_lines_may_use_separators_and_a_prefix(capsys, work):
    write = bench_writes()[0].hex()
    spaced = " ".join(write[i : i + 2] for i in range(0, len(write), 2))
    (work / "writes.txt").write_text(f"  0x{write}\n\n{spaced.upper()}\n")
    code, out, _err = run(
        capsys, "--marker", "12", "--key-file", "site.key", "--replay", "writes.txt"
    )
    assert code == 0
    assert out.splitlines()[-1] == "served 2 writes: 1 accepted, 1 refused (ReplayedWrite 1)"


def test_a_shared_key_file_is_refused(capsys, work):
    os.chmod(work / "site.key", 0o644)  # noqa: PTH101
    replay_file(work / "none.txt")
    code, _out, err = run(capsys, "--marker", "1", "--key-file", "site.key", "--replay", "none.txt")
    assert code == 2
    assert "chmod 600" in err


@pytest.mark.parametrize(
    ("argv", "says"),
    [
        (("--timeout", "nan"), "--timeout"),
        (("--timeout", "-1"), "--timeout"),
        (("--status", "lost"), "--status"),
        (("--urgency", "10"), "--urgency"),
        (("--eink", "tag.gif"), "--eink: 'tag.gif' must end in .png"),
        (("--state-file", "site.key"), "--state-file: 'site.key' is also an input (--key-file)"),
        (("--state-file", "missing/tag.bin"), "folder 'missing' does not exist"),
        (("--adapter", "/org/bluez/hci0"), "--adapter"),
    ],
)
def test_bad_options_are_one_line(capsys, work, argv, says):
    replay_file(work / "none.txt")
    code, out, err = run(
        capsys, "--marker", "1", "--key-file", "site.key", "--replay", "none.txt", *argv
    )
    assert (code, out) == (2, "")
    assert says in err
    assert err.count("\n") == 1


def test_the_replay_option_is_hidden(capsys):
    code, out, _err = run(capsys, "--help")
    assert code == 0
    assert "--state-file" in out
    assert "--replay" not in out


# --- the bless backend end to end, on a private bus with a stand-in for bluetoothd ---------


def test_emulate_serves_writes_over_d_bus(capsys, work, monkeypatch):
    pytest.importorskip("dbus_next")
    from tests.tag.fake_bluez import DAEMON, fake_bluez

    if DAEMON is None:
        pytest.skip("needs dbus-daemon (apt install dbus)")
    writes = bench_writes()
    codes: list[int] = []
    with fake_bluez(work) as bluez:
        monkeypatch.setenv("DBUS_SYSTEM_BUS_ADDRESS", bluez.address)

        def central() -> None:
            deadline = time.monotonic() + 10.0
            while "RegisterAdvertisement" not in bluez.senders and time.monotonic() < deadline:
                time.sleep(0.01)
            codes.extend(bluez.write(value) for value in writes)

        thread = threading.Thread(target=central)
        thread.start()
        code, out, err = run(
            capsys, "--marker", "12", "--key-file", "site.key", "--state-file", "tag.bin",
            "--timeout", "1.5",
        )  # fmt: skip
        thread.join()
    assert (code, err) == (0, "")
    assert codes == [0, 0, 0x81]
    lines = out.splitlines()
    assert lines[0] == (
        "software tag 12 (provisioned in tag.bin) on bless: urgency 0, IDLE, destination 0; "
        "Ctrl-C stops it"
    )
    assert lines[-1] == "served 3 writes: 2 accepted, 1 refused (ReplayedWrite 1)"
    assert [what for what, _ in bluez.log][-2:] == [
        "unregister advertisement",
        "unregister application",
    ]


def test_an_unwritable_eink_folder_leaves_nothing_behind(capsys, work, unwritable_dir):
    replay_file(work / "writes.txt", *bench_writes())
    code, out, err = run(
        capsys, "--marker", "12", "--key-file", "site.key", "--state-file", "tag.bin",
        "--replay", "writes.txt", "--eink", str(unwritable_dir / "tag.png"),
    )  # fmt: skip
    assert (code, out) == (2, "")
    assert err.startswith("swarmtag: error: --eink: ")
    assert not (work / "tag.bin").exists()


def test_an_eink_picture_that_cannot_be_redrawn_stops_the_tag(capsys, work, monkeypatch):
    pytest.importorskip("PIL")
    from swarmtag.tag import eink

    replay_file(work / "writes.txt", *bench_writes())
    drawn: list[Path] = []

    def save_png(state, path):
        drawn.append(Path(path))
        if len(drawn) > 1:
            raise OSError(28, "No space left on device")
        Path(path).write_bytes(b"png")

    monkeypatch.setattr(eink, "save_png", save_png)
    code, out, err = run(
        capsys, "--marker", "12", "--key-file", "site.key", "--replay", "writes.txt",
        "--eink", "tag.png",
    )  # fmt: skip
    assert code == 2
    assert out.splitlines()[1].startswith("accepted from writer 1")
    assert err == "swarmtag: error: --eink: 'tag.png' cannot be written (No space left on device)\n"


def test_a_write_arriving_as_the_tag_goes_live_waits_for_its_state_file(tmp_path):
    pending = tag_emulate._PendingStore()
    tag = SoftwareTag.open(marker=12, site_key=SITE_KEY, store=pending)
    assert pending.load() == pending.held()
    lift = WriteSigner(writer=1, role=Role.OPERATOR, key=OPERATOR).sign(12, Change(urgency=4))
    outcomes = []
    writer = threading.Thread(target=lambda: outcomes.append(tag.write(lift)))
    writer.start()
    time.sleep(0.05)
    assert outcomes == []  # waiting: not acted on before it is persisted
    assert not (tmp_path / "tag.bin").exists()
    FileStore(tmp_path / "tag.bin").save(pending.held())
    pending.commit(FileStore(tmp_path / "tag.bin"))
    writer.join(5.0)
    assert outcomes[0].accepted
    booted = SoftwareTag.boot(site_key=SITE_KEY, store=FileStore(tmp_path / "tag.bin"))
    assert booted.state.urgency == 4


def test_a_write_waiting_for_a_state_file_that_never_comes_fails(tmp_path):
    pending = tag_emulate._PendingStore()
    tag = SoftwareTag.open(marker=12, site_key=SITE_KEY, store=pending)
    pending.commit(None)
    write = WriteSigner(writer=1, role=Role.OPERATOR, key=OPERATOR).sign(12, Change(urgency=4))
    with pytest.raises(OSError, match="never created"):
        tag.write(write)
    assert tag.state.urgency == 0


def test_the_shared_robot_key_is_a_legacy_setting_of_the_tag(capsys, work):
    """Off for a new tag; --shared-robot-key turns it on (saved), --no-shared-robot-key off."""
    shared = WriteSigner(writer=7, role=Role.ROBOT, key=SHARED_ROBOT)
    operator = WriteSigner(writer=1, role=Role.OPERATOR, key=OPERATOR)
    ready = operator.sign(12, Change(status=TagStatus.AWAITING_PICKUP))
    replay_file(work / "a.txt", ready, shared.sign(12, Change(status=TagStatus.PICKED_UP)))
    argv = ("--marker", "12", "--key-file", "site.key", "--state-file", "tag.bin")
    code, out, _err = run(capsys, *argv, "--replay", "a.txt")
    assert code == 0
    assert "ForgedWrite (ATT 0x80)" in out.splitlines()[2]
    replay_file(work / "b.txt", shared.sign(12, Change(status=TagStatus.PICKED_UP)))
    code, out, _err = run(capsys, *argv, "--replay", "b.txt", "--shared-robot-key")
    assert code == 0
    assert out.splitlines()[1] == (
        "note: this tag also accepts the legacy shared robot key (--no-shared-robot-key)"
    )
    assert out.splitlines()[2].startswith("accepted from writer 7 (robot, counter 1)")
    replay_file(work / "c.txt", shared.sign(12, Change(status=TagStatus.IDLE)))
    code, out, _err = run(capsys, *argv, "--replay", "c.txt")  # a stored tag keeps its setting
    assert "accepted from writer 7" in out
    replay_file(work / "d.txt", operator.sign(12, Change(status=TagStatus.AWAITING_PICKUP)),
                shared.sign(12, Change(status=TagStatus.PICKED_UP)))  # fmt: skip
    code, out, _err = run(capsys, *argv, "--replay", "d.txt", "--no-shared-robot-key")
    assert "note:" not in out
    assert "ForgedWrite (ATT 0x80)" in out.splitlines()[2]
    tag = SoftwareTag.boot(site_key=SITE_KEY, store=FileStore(work / "tag.bin"))
    assert (tag.shared_robot_key, tag.state.status) == (False, TagStatus.AWAITING_PICKUP)
