"""The bless software tag, driven through bless's own BlueZ objects: no radio.

Two levels. Without any bus, bless's real server, characteristic and
advertisement objects are built with only the D-Bus boundary replaced (the
message bus and the adapter proxy), and their D-Bus methods are called as
dbus-next calls them. With a private ``dbus-daemon`` (``fake_bluez.py``),
the server runs in its thread as on a laptop, and a stand-in for
bluetoothd registers it, writes to it over D-Bus, reads the error replies
as BlueZ maps them to ATT codes, and hears the notifications and the
advertisement refreshes.
"""

from __future__ import annotations

import asyncio
import importlib
import logging
import sys
from typing import Any

import pytest

pytest.importorskip("bless")
pytest.importorskip("dbus_next")  # bless's BlueZ server: installed with bless on Linux only

from bless.backends.bluezdbus import server as bless_server_module
from dbus_next.errors import DBusError

from swarmtag.errors import ConfigError, RadioError, StateRecordError
from swarmtag.tag import (
    ATT_ERRORS,
    Change,
    MemoryStore,
    Role,
    TagStatus,
    WriteSigner,
    derive_robot_key,
    derive_role_key,
)
from swarmtag.tag.backends.bless import BlessTagServer, dbus_error, explain_server_error
from swarmtag.tag.emulator import SoftwareTag
from swarmtag.tag.gatt import SERVICE_UUID, STATE_CHAR_UUID, WRITE_CHAR_UUID
from tests.tag.fake_bluez import ADVERTISEMENT, CHARACTERISTIC, DAEMON, att_code, fake_bluez

SITE_KEY = bytes(range(32))
MARKER = 12
ROBOT = WriteSigner(writer=7, role=Role.ROBOT, key=derive_robot_key(SITE_KEY, 7))
OPERATOR = WriteSigner(writer=1, role=Role.OPERATOR, key=derive_role_key(SITE_KEY, Role.OPERATOR))


def new_tag(store: MemoryStore | None = None) -> SoftwareTag:
    return SoftwareTag.open(
        marker=MARKER,
        site_key=SITE_KEY,
        store=store or MemoryStore(),
        urgency=7,
        status=TagStatus.AWAITING_PICKUP,
        destination=3,
    )


# --- the ATT codes of refusals, as BlueZ reads the D-Bus errors ----------------------------


@pytest.mark.parametrize(("refusal", "code"), sorted(ATT_ERRORS.items(), key=lambda i: i[1]))
def test_every_refusal_reaches_the_writer_as_its_att_code(refusal, code):
    error = dbus_error(code)
    assert att_code(error.type, error.text) == code, refusal.__name__


def test_the_d_bus_errors_of_refusals():
    assert (dbus_error(0x0D).type, dbus_error(0x0D).text) == (
        "org.bluez.Error.InvalidValueLength",
        "0x0d",
    )
    assert (dbus_error(0x84).type, dbus_error(0x84).text) == ("org.bluez.Error.Failed", "0x84")
    for code in (0x00, 0x0E, 0x7F, 0xA0):
        with pytest.raises(ConfigError, match="application code"):
            dbus_error(code)


@pytest.mark.parametrize(
    ("error", "says"),
    [
        (FileNotFoundError(2, "No such file or directory"), "BlueZ is not reachable"),
        (ConnectionRefusedError(111, "Connection refused"), "BlueZ is not reachable"),
        (DBusError("org.freedesktop.DBus.Error.ServiceUnknown", "no org.bluez"), "BlueZ is not"),
        (DBusError("org.freedesktop.DBus.Error.AccessDenied", "denied"), "permission denied"),
        (DBusError("org.bluez.Error.NotReady", "Resource Not Ready"), "bluetoothctl power on"),
        (Exception("No adapter named hci0 found"), "no Bluetooth adapter found"),
        (
            DBusError("org.bluez.Error.NotPermitted", "Maximum advertisements reached"),
            "cannot take another advertisement",
        ),
    ],
)
def test_radio_errors_are_explained_in_one_line(error, says):
    line = explain_server_error(error)
    assert says in line
    assert "\n" not in line


# --- bless's objects with only the D-Bus boundary replaced ---------------------------------


class Recorder:
    """A D-Bus proxy interface: every ``call_*`` is recorded and answers nothing."""

    def __init__(self, name: str, calls: list[tuple[str, str, tuple[Any, ...]]]) -> None:
        self.name = name
        self.calls = calls

    def __getattr__(self, member: str) -> Any:
        async def call(*args: Any) -> None:
            self.calls.append((self.name, member, args))

        return call


class FakeAdapter:
    def __init__(self) -> None:
        self.calls: list[tuple[str, str, tuple[Any, ...]]] = []

    def get_interface(self, name: str) -> Recorder:
        return Recorder(name, self.calls)


class FakeBus:
    """dbus-next's MessageBus as bless uses it: connect, export, unexport, disconnect."""

    made: list[FakeBus] = []  # noqa: RUF012 - per-test, reset by the fixture

    def __init__(self, **_options: Any) -> None:
        self.exported: dict[str, Any] = {}
        self.connected = False
        type(self).made.append(self)

    async def connect(self) -> FakeBus:
        self.connected = True
        return self

    def export(self, path: str, interface: Any) -> None:
        self.exported[path] = interface

    def unexport(self, path: str, interface: Any = None) -> None:
        self.exported.pop(path, None)

    def disconnect(self) -> None:
        self.connected = False


@pytest.fixture
def no_dbus(monkeypatch, tmp_path):
    """bless's BlueZ server with a fake bus and adapter: everything else is bless's own."""
    socket = tmp_path / "system_bus_socket"  # what the pre-check looks for before connecting
    socket.touch()
    monkeypatch.setenv("DBUS_SYSTEM_BUS_ADDRESS", f"unix:path={socket}")
    adapter = FakeAdapter()
    FakeBus.made = []

    async def get_adapter(_bus: Any, _name: str | None = None) -> FakeAdapter:
        return adapter

    monkeypatch.setattr(bless_server_module, "MessageBus", FakeBus)
    monkeypatch.setattr(bless_server_module, "get_adapter", get_adapter)
    return adapter


def dbus_method(interface: Any, name: str) -> Any:
    """The function dbus-next runs for a D-Bus method call of ``name`` on ``interface``."""
    return getattr(type(interface), name).__dict__["__DBUS_METHOD"].fn


def opened(tag: SoftwareTag) -> tuple[BlessTagServer, asyncio.AbstractEventLoop]:
    server = BlessTagServer(tag)
    loop = asyncio.new_event_loop()
    loop.run_until_complete(server.open(loop))
    return server, loop


def test_the_service_and_advertisement_bless_registers(no_dbus):
    server, loop = opened(new_tag())
    bless = server.bless_server
    try:
        write = bless.get_characteristic(WRITE_CHAR_UUID).gatt
        state = bless.get_characteristic(STATE_CHAR_UUID).gatt
        assert (write.Flags, state.Flags) == (["write"], ["read", "notify"])
        assert state.Value == b"\x07\x01\x03\x0c"
        advert = server._advertisement
        assert advert.ServiceUUIDs == [SERVICE_UUID]
        assert {k: v.value for k, v in advert.ManufacturerData.items()} == {
            0xFFFF: b"\x07\x01\x03\x0c"
        }
        assert advert.Type == "peripheral"
        assert advert.LocalName == "swarmtag-12"
        members = [(interface, member) for interface, member, _ in no_dbus.calls]
        assert members == [
            ("org.bluez.GattManager1", "call_register_application"),
            ("org.freedesktop.DBus.Properties", "call_set"),
            ("org.bluez.LEAdvertisingManager1", "call_register_advertisement"),
        ]
        assert no_dbus.calls[2][2] == (advert.path, {})
        assert FakeBus.made[0].exported[advert.path] is advert
    finally:
        loop.run_until_complete(server.close())
        loop.close()
    assert [member for _, member, _ in no_dbus.calls[3:]] == [
        "call_set",
        "call_unregister_advertisement",
        "call_unregister_application",
    ]
    assert not FakeBus.made[0].connected


def test_an_accepted_write_updates_the_notify_value_and_the_advert(no_dbus, monkeypatch):
    tag = new_tag()
    server, loop = opened(tag)
    bless = server.bless_server
    write = bless.get_characteristic(WRITE_CHAR_UUID).gatt
    state = bless.get_characteristic(STATE_CHAR_UUID).gatt
    advert = server._advertisement
    emitted: list[tuple[str, dict[str, Any]]] = []
    for obj in (state, advert):

        def spy(changed_properties: dict[str, Any], *_rest: Any, path: str = obj.path) -> None:
            emitted.append((path, changed_properties))

        monkeypatch.setattr(obj, "emit_properties_changed", spy)
    try:
        dbus_method(write, "WriteValue")(
            write, ROBOT.sign(MARKER, Change(status=TagStatus.PICKED_UP)), {}
        )
        assert dbus_method(state, "ReadValue")(state, {}) == b"\x07\x02\x03\x0c"
        assert state.Value == b"\x07\x02\x03\x0c"
        assert advert.ManufacturerData[0xFFFF].value == b"\x07\x02\x03\x0c"
        assert emitted[0] == (state.path, {"Value": b"\x07\x02\x03\x0c"})  # the notification
        assert emitted[1][0] == advert.path
        assert emitted[1][1]["ManufacturerData"][0xFFFF].value == b"\x07\x02\x03\x0c"
        [outcome] = server.outcomes()
        assert outcome.accepted
        assert outcome.state.status is TagStatus.PICKED_UP
    finally:
        loop.run_until_complete(server.close())
        loop.close()


@pytest.mark.parametrize(
    ("message", "name", "text"),
    [
        (ROBOT.sign(MARKER, Change(urgency=1)), "org.bluez.Error.Failed", "0x83"),
        (OPERATOR.sign(MARKER + 1, Change(urgency=1)), "org.bluez.Error.Failed", "0x82"),
        (b"\x01\x02", "org.bluez.Error.InvalidValueLength", "0x0d"),
        (bytes(20), "org.bluez.Error.Failed", "0x80"),
    ],
)
def test_a_refused_write_answers_its_error_and_changes_nothing(no_dbus, message, name, text):
    tag = new_tag()
    server, loop = opened(tag)
    bless = server.bless_server
    write = bless.get_characteristic(WRITE_CHAR_UUID).gatt
    state = bless.get_characteristic(STATE_CHAR_UUID).gatt
    try:
        with pytest.raises(DBusError) as refused:
            dbus_method(write, "WriteValue")(write, message, {})
        assert (refused.value.type, refused.value.text) == (name, text)
        assert state.Value == b"\x07\x01\x03\x0c" == tag.state_value()
        assert server._advertisement.ManufacturerData[0xFFFF].value == b"\x07\x01\x03\x0c"
        assert [o.att_error for o in server.outcomes()] == [int(text, 16)]
    finally:
        loop.run_until_complete(server.close())
        loop.close()


def test_only_state_reads_and_only_write_writes(no_dbus):
    server, loop = opened(new_tag())
    bless = server.bless_server
    write = bless.get_characteristic(WRITE_CHAR_UUID)
    state = bless.get_characteristic(STATE_CHAR_UUID)
    try:
        with pytest.raises(DBusError, match="only the state"):
            server.read_request(write)
        with pytest.raises(DBusError, match="only the write"):
            server.write_request(state, OPERATOR.sign(MARKER, Change(urgency=1)))
        assert server.outcomes() == []
    finally:
        loop.run_until_complete(server.close())
        loop.close()


class BrokenStore(MemoryStore):
    def __init__(self) -> None:
        super().__init__()
        self.broken = False

    def save(self, record: bytes) -> None:
        if self.broken:
            raise OSError(28, "No space left on device")
        super().save(record)


def test_a_store_failure_answers_unlikely_error_and_stops_the_server(no_dbus):
    store = BrokenStore()
    tag = new_tag(store)
    server, loop = opened(tag)
    write = server.bless_server.get_characteristic(WRITE_CHAR_UUID)
    store.broken = True
    try:
        with pytest.raises(DBusError) as failed:
            server.write_request(write, OPERATOR.sign(MARKER, Change(urgency=0)))
        assert att_code(failed.value.type, failed.value.text) == 0x0E
        assert isinstance(server.failure, StateRecordError)
        assert "could not be saved" in str(server.failure)
        assert tag.state.urgency == 7
    finally:
        loop.run_until_complete(server.close())
        loop.close()


def test_missing_bless_is_one_line_naming_the_extra(monkeypatch):
    monkeypatch.setitem(sys.modules, "bless.backends.attribute", None)  # as if not installed
    monkeypatch.delitem(sys.modules, "swarmtag.tag.backends.bless")
    with pytest.raises(ConfigError) as missing:
        importlib.import_module("swarmtag.tag.backends.bless")
    assert str(missing.value) == (
        "the software tag needs the bless package, which is not installed: "
        "pip install 'swarmtag[tag-emulator]'"
    )


def test_bad_options_are_refused():
    tag = new_tag()
    with pytest.raises(ConfigError, match="local_name"):
        BlessTagServer(tag, local_name="two\nlines")
    with pytest.raises(ConfigError, match="adapter"):
        BlessTagServer(tag, adapter="/org/bluez/hci0")
    assert BlessTagServer(tag, adapter="hci1").adapter == "hci1"
    with pytest.raises(ConfigError, match="start_timeout"):
        BlessTagServer(tag, start_timeout=float("nan"))


# --- the whole server on a private bus, with a stand-in for bluetoothd --------------------

needs_daemon = pytest.mark.skipif(DAEMON is None, reason="needs dbus-daemon (apt install dbus)")


@pytest.fixture
def bluez(tmp_path, monkeypatch):
    with fake_bluez(tmp_path) as fake:
        monkeypatch.setenv("DBUS_SYSTEM_BUS_ADDRESS", fake.address)
        yield fake


def wait_for(predicate: Any, seconds: float = 5.0) -> None:
    import time

    deadline = time.monotonic() + seconds
    while not predicate():
        assert time.monotonic() < deadline, "timed out"
        time.sleep(0.01)


@needs_daemon
def test_a_central_writes_over_d_bus_and_hears_each_change(bluez, caplog):
    tag = new_tag()
    with BlessTagServer(tag, start_timeout=10.0) as server:
        assert server.failure is None
        assert server.serving
        objects = bluez.objects()
        chars = bluez.characteristics()
        assert set(chars) == {WRITE_CHAR_UUID, STATE_CHAR_UUID}
        assert objects[chars[STATE_CHAR_UUID]][CHARACTERISTIC]["Flags"] == ["read", "notify"]
        advert = bluez.advertisement()
        assert advert["ManufacturerData"][0xFFFF].value == b"\x07\x01\x03\x0c"
        assert advert["ServiceUUIDs"] == [SERVICE_UUID]
        assert bluez.adapter.alias == "swarmtag-12"

        lift = ROBOT.sign(MARKER, Change(status=TagStatus.PICKED_UP))
        assert bluez.write(lift) == 0
        read = bluez.call(chars[STATE_CHAR_UUID], CHARACTERISTIC, "ReadValue", "a{sv}", {})
        assert read.body == [b"\x07\x02\x03\x0c"]
        assert bluez.advertisement()["ManufacturerData"][0xFFFF].value == b"\x07\x02\x03\x0c"
        wait_for(lambda: len(bluez.signals) >= 2)
        notify, refresh = bluez.signals[:2]
        assert notify == (chars[STATE_CHAR_UUID], CHARACTERISTIC, {"Value": b"\x07\x02\x03\x0c"})
        assert refresh[1] == ADVERTISEMENT
        assert refresh[2]["ManufacturerData"][0xFFFF].value == b"\x07\x02\x03\x0c"

        with caplog.at_level(logging.DEBUG):
            assert bluez.write(lift) == 0x81  # replayed
            assert bluez.write(ROBOT.sign(MARKER, Change(urgency=9))) == 0x83  # wrong role
            forged = WriteSigner(writer=7, role=Role.OPERATOR, key=ROBOT.key)
            assert bluez.write(forged.sign(MARKER, Change(urgency=9))) == 0x80
            assert bluez.write(b"\x01") == 0x0D
        assert not [r for r in caplog.records if "unexpected error" in r.getMessage()]
        assert len(bluez.signals) == 2  # refusals notify nothing, refresh nothing
        assert tag.state_value() == b"\x07\x02\x03\x0c"
        outcomes = server.outcomes()
        assert [o.att_error for o in outcomes] == [None, 0x81, 0x83, 0x80, 0x0D]
    assert not server.serving
    assert [what for what, _ in bluez.log] == [
        "register application",
        "register advertisement",
        "unregister advertisement",
        "unregister application",
    ]


@needs_daemon
@pytest.mark.parametrize(
    ("options", "says"),
    [
        ({"own_name": False}, "BlueZ is not reachable"),
        ({"adapter": False}, "no Bluetooth adapter found"),
    ],
)
def test_a_bus_without_bluez_or_adapter_is_one_radio_error(tmp_path, monkeypatch, options, says):
    with fake_bluez(tmp_path, **options) as fake:
        monkeypatch.setenv("DBUS_SYSTEM_BUS_ADDRESS", fake.address)
        server = BlessTagServer(new_tag(), start_timeout=10.0)
        server.start()
        server.stop()
    assert isinstance(server.failure, RadioError)
    assert says in str(server.failure)
    assert not server.serving


def test_no_system_bus_is_one_radio_error(tmp_path, monkeypatch):
    monkeypatch.setenv("DBUS_SYSTEM_BUS_ADDRESS", f"unix:path={tmp_path / 'no-bus'}")
    server = BlessTagServer(new_tag())
    server.start()
    server.stop()
    assert isinstance(server.failure, RadioError)
    assert str(server.failure).startswith("BlueZ is not reachable")


# --- opt-in: the real adapter -------------------------------------------------------------

RADIO_SECONDS = 10.0


@pytest.mark.radio
def test_serve_ten_seconds_on_this_adapter():
    """BlueZ takes the service and the advertisement; scan for marker 201 from another machine."""
    tag = SoftwareTag.open(marker=201, site_key=SITE_KEY, store=MemoryStore(), urgency=5)
    with BlessTagServer(tag) as server:
        assert server.failure is None, str(server.failure)
        assert server.serving
        print(f"advertising marker 201 as {server.local_name!r} for {RADIO_SECONDS:g} s")
        import time

        deadline = time.monotonic() + RADIO_SECONDS
        while time.monotonic() < deadline and server.failure is None:
            time.sleep(0.1)
        for outcome in server.outcomes():
            print(outcome)
    assert server.failure is None, str(server.failure)
