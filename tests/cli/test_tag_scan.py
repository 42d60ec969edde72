"""``swarmtag tag scan`` with the fake and sim backends: table, JSON, Ctrl-C, radio failures."""

from __future__ import annotations

import json

import pytest

from swarmtag.cli import main, tag_scan
from swarmtag.errors import ConfigError, RadioError
from swarmtag.tag.backends.fake import FakeScanner


def run(capsys, *argv: str) -> tuple[int, str, str]:
    with pytest.raises(SystemExit) as exited:
        main(["tag", "scan", *argv])
    out, err = capsys.readouterr()
    return int(exited.value.code or 0), out, err


class Clock:
    def __init__(self) -> None:
        self.now = 10.0

    def __call__(self) -> float:
        return self.now


@pytest.fixture
def fake(monkeypatch):
    clock = Clock()
    scanner = FakeScanner(clock=clock)
    scanner.feed("AA:01", {0xFFFF: bytes([9, 1, 2, 12])}, rssi=-51)
    scanner.feed("PHONE", {0x004C: b"\x02\x15"})
    scanner.feed("BROKEN", {0xFFFF: b"\x0a\x01\x02\x0c"})
    clock.now = 11.5
    monkeypatch.setattr(tag_scan, "_open", lambda backend, adapter: scanner)
    return scanner


def test_table_of_tags_in_range(capsys, fake):
    code, out, err = run(capsys, "--timeout", "0")
    assert (code, err) == (0, "")
    row = next(line for line in out.splitlines() if "AWAITING_PICKUP" in line)
    assert [cell.strip() for cell in row.strip("│ ").split("│")] == [
        "12",
        "9",
        "AWAITING_PICKUP",
        "2",
        "-51",
        "1.5",
        "AA:01",
    ]
    assert "heard 1 adverts of our tags; ignored 1 of other devices; 1 malformed" in out
    assert fake.starts == 1
    assert not fake.running


def test_json_is_one_object(capsys, fake):
    code, out, _err = run(capsys, "--timeout", "0", "--json")
    assert code == 0
    assert json.loads(out) == {
        "backend": "bleak",
        "tags": [
            {
                "marker": 12,
                "urgency": 9,
                "status": "AWAITING_PICKUP",
                "destination": 2,
                "rssi": -51,
                "age_s": 1.5,
                "address": "AA:01",
            }
        ],
        "accepted": 1,
        "foreign": 1,
        "malformed": 1,
    }


def test_nothing_in_range(capsys, monkeypatch):
    monkeypatch.setattr(tag_scan, "_open", lambda backend, adapter: FakeScanner())
    code, out, _err = run(capsys, "--timeout", "0")
    assert code == 0
    assert out.startswith("no tags in range\n")


def test_radio_failure_is_one_line_exit_2(capsys, monkeypatch):
    scanner = FakeScanner()
    scanner.fail(RadioError("no Bluetooth adapter found: plug in a BLE adapter"))
    monkeypatch.setattr(tag_scan, "_open", lambda backend, adapter: scanner)
    code, out, err = run(capsys, "--timeout", "5")
    assert (code, out) == (2, "")
    assert err == "swarmtag: error: no Bluetooth adapter found: plug in a BLE adapter\n"


def test_missing_ble_extra_is_one_line_exit_2(capsys, monkeypatch):
    def missing(backend, adapter):
        raise ConfigError(
            "backend 'bleak' needs the bleak package, which is not installed: pip install 'swarmtag[ble]'"
        )

    monkeypatch.setattr(tag_scan, "_open", missing)
    code, _out, err = run(capsys)
    assert code == 2
    assert err.count("\n") == 1
    assert "swarmtag[ble]" in err


class Interrupted(FakeScanner):
    def poll(self) -> None:
        raise KeyboardInterrupt


def test_ctrl_c_shows_what_was_seen_then_exits_130(capsys, monkeypatch):
    scanner = Interrupted()
    scanner.feed("AA:01", {0xFFFF: bytes([3, 0, 1, 7])})
    monkeypatch.setattr(tag_scan, "_open", lambda backend, adapter: scanner)
    code, out, err = run(capsys, "--timeout", "60", "--json")
    assert code == 130
    assert [tag["marker"] for tag in json.loads(out)["tags"]] == [7]
    assert err.startswith("swarmtag: error: aborted; scan ended by Ctrl-C")
    assert not scanner.running


def test_sim_backend_hears_the_bench(capsys):
    code, out, _err = run(capsys, "--backend", "sim", "--timeout", "0.3", "--json")
    assert code == 0
    assert {tag["marker"] for tag in json.loads(out)["tags"]} <= {7, 12, 21}
    assert json.loads(out)["foreign"] == 0


@pytest.mark.parametrize("timeout", ["nan", "inf", "-1", "1e9", "x"])
def test_bad_timeouts_are_refused(capsys, timeout):
    code, out, err = run(capsys, "--backend", "sim", "--timeout", timeout)
    assert (code, out) == (2, "")
    assert "--timeout" in err


def test_the_backend_option_is_hidden(capsys):
    code, out, _err = run(capsys, "--help")
    assert code == 0
    assert "--timeout" in out
    assert "--backend" not in out


def test_adapter_reaches_the_scanner(capsys, monkeypatch):
    asked = []

    def opened(backend, adapter):
        asked.append((backend, adapter))
        return FakeScanner()

    monkeypatch.setattr(tag_scan, "_open", opened)
    code, _out, _err = run(capsys, "--timeout", "0", "--adapter", "hci1")
    assert code == 0
    assert asked == [("bleak", "hci1")]
    assert run(capsys, "--timeout", "0")[0] == 0
    assert asked[-1] == ("bleak", None)


@pytest.mark.parametrize("adapter", ["eth0", "hci", "HCI0", "hci0 ", ""])
def test_a_bad_adapter_is_one_line_exit_2(capsys, adapter):
    code, out, err = run(capsys, "--timeout", "0", "--adapter", adapter)
    assert (code, out) == (2, "")
    assert "not a BlueZ adapter name such as hci0 or hci1" in err
    assert err.count("\n") == 1


def test_the_bleak_backend_gets_the_adapter():
    pytest.importorskip("bleak")
    scanner = tag_scan._open("bleak", "hci2")
    assert scanner.adapter == "hci2"
