"""The bleak backend, driven with bleak's own BLEDevice and AdvertisementData: no radio.

The detection callback gets the objects bleak's platform backends build;
the retry path runs the real scanner thread with a fake BleakScanner class.
"""

from __future__ import annotations

import asyncio
import inspect
import threading
import time

import pytest

pytest.importorskip("bleak")

from bleak.backends.device import BLEDevice
from bleak.backends.scanner import AdvertisementData
from bleak.exc import BleakDBusError, BleakError

from swarmtag.errors import RadioError
from swarmtag.tag import TagState, TagStatus
from swarmtag.tag.backends import open_scanner
from swarmtag.tag.backends.bleak import BleakTagScanner, adapter_options, explain

OURS = {0xFFFF: bytes([7, 1, 3, 12])}


class Clock:
    def __init__(self, now: float = 50.0) -> None:
        self.now = now

    def __call__(self) -> float:
        return self.now


def device(address: str = "AA:BB:CC:DD:EE:01", name: str | None = "tag") -> BLEDevice:
    """A BLEDevice as bleak's backends build it (bleak < 0.23 still wants rssi)."""
    if "rssi" in inspect.signature(BLEDevice).parameters:
        return BLEDevice(address, name, None, -60)
    return BLEDevice(address, name, None)


def advert(manufacturer_data: dict[int, bytes], rssi: int = -60) -> AdvertisementData:
    """AdvertisementData with every field, as bleak's own tests construct it."""
    return AdvertisementData(
        local_name=None,
        manufacturer_data=manufacturer_data,
        service_data={},
        service_uuids=[],
        tx_power=None,
        rssi=rssi,
        platform_data=(),
    )


def hear(scanner: BleakTagScanner, address: str, data: dict[int, bytes], rssi: int = -60) -> None:
    scanner.detection_callback(device(address), advert(data, rssi))


def test_facade_opens_the_bleak_backend():
    assert isinstance(open_scanner("bleak"), BleakTagScanner)


def test_ours_is_kept_with_rssi_time_and_address():
    scanner = BleakTagScanner(clock=Clock())
    hear(scanner, "AA:01", OURS, rssi=-48)
    held = scanner.states()[12]
    assert (held.rssi, held.seen_at, held.address) == (-48, 50.0, "AA:01")
    assert held.state == TagState(
        urgency=7, status=TagStatus.AWAITING_PICKUP, destination=3, marker=12
    )


def test_foreign_devices_are_ignored():
    scanner = BleakTagScanner(clock=Clock())
    hear(scanner, "PHONE", {0x004C: b"\x02\x15\x00"})  # an iBeacon
    hear(scanner, "WATCH", {})  # no manufacturer data at all
    hear(scanner, "TV", {0x0075: b"\x42\x04"})
    assert scanner.states() == {}
    assert (scanner.accepted, scanner.foreign, scanner.malformed) == (0, 3, 0)


def test_malformed_ours_are_counted_not_crashed():
    scanner = BleakTagScanner(clock=Clock())
    for data in (b"\x0a\x01\x03\x0c", b"\x07\x07\x03\x0c"):
        hear(scanner, "BROKEN", {0xFFFF: data})
    hear(scanner, "GOOD", OURS)
    assert list(scanner.states()) == [12]
    assert scanner.malformed == 2
    assert scanner.errors == {"UrgencyRangeError": 1, "UnknownStatusError": 1}


def test_other_devices_under_0xffff_are_foreign_not_malformed():
    """0xFFFF is the test/internal-use id: battery monitors and beacons use it too (issue 35)."""
    scanner = BleakTagScanner(clock=Clock())
    for data in (b"", b"\x07", b"\x07\x01\x03", b"\x07\x01\x03\x0c\x00", bytes(20)):
        hear(scanner, "MONITOR", {0xFFFF: data})
    hear(scanner, "GOOD", OURS)
    assert list(scanner.states()) == [12]
    assert (scanner.accepted, scanner.foreign, scanner.malformed) == (1, 5, 0)


def test_updates_are_seen_when_adverts_repeat_or_are_dropped():
    clock = Clock()
    scanner = BleakTagScanner(clock=clock)
    for _ in range(3):  # the stack repeats an unchanged advert
        hear(scanner, "AA", OURS)
        clock.now += 0.25
    clock.now += 2.0  # several adverts dropped
    hear(scanner, "AA", {0xFFFF: bytes([7, 2, 3, 12])}, rssi=-70)  # picked up
    held = scanner.states()[12]
    assert (held.state.status, held.rssi, held.seen_at) == (TagStatus.PICKED_UP, -70, clock.now)
    assert scanner.accepted == 4


def test_stale_states_age_out():
    clock = Clock()
    scanner = BleakTagScanner(clock=clock, max_age=3.0)
    hear(scanner, "AA", OURS)
    hear(scanner, "BB", {0xFFFF: bytes([1, 0, 0, 40])})
    clock.now += 2.0
    hear(scanner, "BB", {0xFFFF: bytes([1, 0, 0, 40])})
    clock.now += 2.0
    assert list(scanner.states()) == [40]
    clock.now += 10.0
    assert scanner.states() == {}


# --- the thread, with a fake BleakScanner class ------------------------------------------------


class FakeBleak:
    """Stands in for bleak.BleakScanner: fails ``failures`` times, then hears one advert."""

    failures = 0
    error: BaseException = BleakError("org.bluez.Error.Failed: adapter busy")
    made: list[FakeBleak] = []  # noqa: RUF012 - per-test class state, reset by the fixture

    def __init__(self, detection_callback, **options) -> None:
        self.callback = detection_callback
        self.options = options
        self.stopped = False
        type(self).made.append(self)

    async def start(self) -> None:
        if len(type(self).made) <= type(self).failures:
            raise type(self).error
        await asyncio.sleep(0)
        self.callback(device("AA:01"), advert(OURS, rssi=-55))

    async def stop(self) -> None:
        self.stopped = True


@pytest.fixture
def fake_bleak():
    class Fresh(FakeBleak):
        made: list[FakeBleak] = []  # noqa: RUF012

    return Fresh


def wait_for(condition, seconds: float = 5.0) -> None:
    deadline = time.monotonic() + seconds
    while not condition():
        assert time.monotonic() < deadline, "condition not met in time"
        time.sleep(0.01)


def test_thread_scans_and_stop_joins(fake_bleak):
    scanner = BleakTagScanner(scanner_factory=fake_bleak)
    with scanner:
        wait_for(lambda: 12 in scanner.states())
        assert scanner.scanning
    assert not scanner.scanning
    assert fake_bleak.made[0].stopped
    assert fake_bleak.made[0].options == {"scanning_mode": "active"}
    assert not any(t.name == "swarmtag-bleak" for t in threading.enumerate())
    assert scanner.failure is None


def test_adapter_errors_are_retried_with_backoff_then_scanning_works(fake_bleak, caplog):
    fake_bleak.failures = 2
    scanner = BleakTagScanner(scanner_factory=fake_bleak, retries=3, backoff=0.01)
    with caplog.at_level("WARNING", logger="swarmtag.tag.backends.bleak"), scanner:
        wait_for(lambda: 12 in scanner.states())
    assert scanner.attempts == 3
    assert scanner.failure is None
    assert [r.message.split(";")[1].strip() for r in caplog.records] == [
        "retry 1 of 3 in 0.01 s",
        "retry 2 of 3 in 0.02 s",
    ]


def test_retries_are_bounded_then_the_scanner_reports_failed(fake_bleak):
    fake_bleak.failures = 100
    scanner = BleakTagScanner(scanner_factory=fake_bleak, retries=2, backoff=0.0)
    scanner.start()
    wait_for(lambda: scanner.failure is not None)
    scanner.stop()
    assert scanner.attempts == 3
    assert isinstance(scanner.failure, RadioError)
    assert "adapter busy" in str(scanner.failure)
    assert "gave up after 3 attempts" in str(scanner.failure)


@pytest.mark.parametrize(
    ("error", "says"),
    [
        (FileNotFoundError(2, "No such file or directory"), "sudo apt install bluez"),
        (PermissionError(13, "Permission denied"), "usermod -aG bluetooth"),
        (BleakError("No Bluetooth adapters found."), "no Bluetooth adapter found"),
        (BleakDBusError("org.freedesktop.DBus.Error.AccessDenied", []), "permission denied"),
        (BleakError("adapter 'hci5' not found"), "no Bluetooth adapter 'hci5' not found"),
    ],
)
def test_errors_no_retry_can_fix_fail_at_once_and_say_how_to_fix(fake_bleak, error, says):
    fake_bleak.failures = 100
    fake_bleak.error = error
    scanner = BleakTagScanner(scanner_factory=fake_bleak, retries=5, backoff=0.0)
    scanner.start()
    wait_for(lambda: scanner.failure is not None)
    scanner.stop()
    assert scanner.attempts == 1
    assert says in str(scanner.failure)
    assert "\n" not in str(scanner.failure)


def test_stop_interrupts_the_backoff(fake_bleak):
    fake_bleak.failures = 100
    scanner = BleakTagScanner(scanner_factory=fake_bleak, retries=3, backoff=30.0)
    scanner.start()
    wait_for(lambda: scanner.attempts == 1)
    started = time.monotonic()
    scanner.stop()
    assert time.monotonic() - started < 2.0
    assert scanner.failure is None


def test_an_unexpected_crash_becomes_a_failure(fake_bleak):
    fake_bleak.failures = 100
    fake_bleak.error = RuntimeError("boom")
    scanner = BleakTagScanner(scanner_factory=fake_bleak)
    scanner.start()
    wait_for(lambda: scanner.failure is not None)
    scanner.stop()
    assert "the BLE scanner stopped" in str(scanner.failure)


def test_explain_names_powered_off_adapters():
    reasons = pytest.importorskip("bleak.exc")
    if not hasattr(reasons, "BleakBluetoothNotAvailableError"):
        pytest.skip("bleak < 1.0 has no BleakBluetoothNotAvailableError")
    error = reasons.BleakBluetoothNotAvailableError(
        "off", reasons.BleakBluetoothNotAvailableReason.POWERED_OFF
    )
    assert "bluetoothctl power on" in explain(error)


def test_the_adapter_reaches_the_scanner_the_way_bleak_takes_it(fake_bleak):
    scanner = BleakTagScanner(scanner_factory=fake_bleak, adapter="hci1")
    with scanner:
        wait_for(lambda: 12 in scanner.states())
    options = fake_bleak.made[0].options
    assert options.pop("scanning_mode") == "active"
    assert options == adapter_options("hci1")
    assert options in ({"bluez": {"adapter": "hci1"}}, {"adapter": "hci1"})
    # bleak's own scanner takes exactly those options (a deprecation warning would be an error)
    import bleak

    real = bleak.BleakScanner(detection_callback=scanner.detection_callback, **options)
    assert real is not None


def test_adapter_options_follow_the_installed_bleak(monkeypatch):
    import sys
    import types

    assert adapter_options(None) == {} == adapter_options(None, client=True)
    new = types.ModuleType("bleak.args.bluez")  # bleak >= 3.0: the adapter is a BlueZ arg
    new.BlueZScannerArgs = type("BlueZScannerArgs", (), {"__annotations__": {"adapter": str}})
    new.BlueZClientArgs = type("BlueZClientArgs", (), {"__annotations__": {"adapter": str}})
    monkeypatch.setitem(sys.modules, "bleak.args.bluez", new)
    assert adapter_options("hci2") == {"bluez": {"adapter": "hci2"}}
    assert adapter_options("hci2", client=True) == {"bluez": {"adapter": "hci2"}}
    old = types.ModuleType("bleak.args.bluez")  # bleak 1.x / 2.x: scanner args without it
    old.BlueZScannerArgs = type("BlueZScannerArgs", (), {"__annotations__": {"filters": dict}})
    monkeypatch.setitem(sys.modules, "bleak.args.bluez", old)
    assert adapter_options("hci2") == {"adapter": "hci2"}
    assert adapter_options("hci2", client=True) == {"adapter": "hci2"}
    monkeypatch.setitem(sys.modules, "bleak.args.bluez", None)  # bleak < 1.0: no bleak.args
    assert adapter_options("hci2") == {"adapter": "hci2"}


@pytest.mark.parametrize(
    ("option", "value"),
    [
        ("retries", -1),
        ("retries", 1.5),
        ("scanning_mode", "loud"),
        ("backoff", float("inf")),
        ("adapter", "wlan0"),
        ("adapter", "hci"),
        ("adapter", "hci0\n"),
        ("adapter", 0),
    ],
)
def test_bad_options_are_refused(option, value):
    from swarmtag.errors import ConfigError

    with pytest.raises(ConfigError, match=option):
        BleakTagScanner(**{option: value})
