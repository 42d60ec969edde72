"""A private D-Bus bus with a stand-in for bluetoothd, for the software tag's tests.

``FakeBluez`` starts its own ``dbus-daemon`` (never the system bus) and owns
the name ``org.bluez`` on it with what bless talks to: an adapter object
``/org/bluez/hci0`` with ``Adapter1`` (its ``Alias``), ``GattManager1`` and
``LEAdvertisingManager1``. It records who registered what, and then does
what bluetoothd does with a registered application: reads its objects,
calls ``WriteValue``/``ReadValue`` on its characteristics and listens for
``PropertiesChanged`` (notifications, advertisement refreshes).
``att_code`` is BlueZ's own mapping of a D-Bus error reply to the ATT error
of the write response (src/gatt-database.c, BlueZ 5.66 and later).
"""

# ruff: noqa: F722, F821, N802 - dbus-next reads D-Bus signatures from the annotations; BlueZ names

import asyncio
import contextlib
import shutil
import subprocess
import threading
from collections.abc import Coroutine, Iterator
from pathlib import Path
from typing import Any, TypeVar

from dbus_next import Message, MessageType
from dbus_next.aio import MessageBus
from dbus_next.constants import PropertyAccess
from dbus_next.service import ServiceInterface, dbus_property, method

T = TypeVar("T")

DAEMON = shutil.which("dbus-daemon")
"""The D-Bus daemon binary, or None (then the tests that need a bus are skipped)."""
CHARACTERISTIC = "org.bluez.GattCharacteristic1"
ADVERTISEMENT = "org.bluez.LEAdvertisement1"
PROPERTIES = "org.freedesktop.DBus.Properties"

_CONFIG = """<!DOCTYPE busconfig PUBLIC "-//freedesktop//DTD D-Bus Bus Configuration 1.0//EN"
 "http://www.freedesktop.org/standards/dbus/1.0/busconfig.dtd">
<busconfig>
  <type>session</type>
  <listen>unix:path={path}</listen>
  <auth>EXTERNAL</auth>
  <policy context="default">
    <allow send_destination="*" eavesdrop="true"/>
    <allow eavesdrop="true"/>
    <allow own="*"/>
  </policy>
</busconfig>
"""

# BlueZ's dbus_error_to_att_ecode: the error names it knows and the ATT codes they become.
_BLUEZ_CODES = {
    "org.bluez.Error.NotSupported": 0x06,
    "org.bluez.Error.NotAuthorized": 0x08,
    "org.bluez.Error.InvalidValueLength": 0x0D,
    "org.bluez.Error.InvalidOffset": 0x07,
    "org.bluez.Error.NotPermitted": 0x03,  # the "permission error" of a write
}
_UNLIKELY = 0x0E


def att_code(error_name: str, message: str) -> int:
    """The ATT error BlueZ answers for a write whose ``WriteValue`` replied with this error."""
    if error_name == "org.bluez.Error.Failed":
        try:
            code = int(message, 0)  # strtol(msg, &end, 0), and the whole message must parse
        except ValueError:
            return 0x80
        return code if 0x80 <= code <= 0x9F else _UNLIKELY
    return _BLUEZ_CODES.get(error_name, _UNLIKELY)


class _Root(ServiceInterface):
    def __init__(self) -> None:
        super().__init__("org.bluez.AgentManager1")  # anything at "/": it makes "/" introspectable


class _Adapter(ServiceInterface):
    def __init__(self) -> None:
        super().__init__("org.bluez.Adapter1")
        self.alias = "laptop"

    @dbus_property()
    def Alias(self) -> "s":
        return self.alias

    @Alias.setter
    def Alias(self, value: "s"):
        self.alias = value


class _GattManager(ServiceInterface):
    def __init__(self, log: list[tuple[str, str]]) -> None:
        super().__init__("org.bluez.GattManager1")
        self.log = log

    @method()
    def RegisterApplication(self, path: "o", options: "a{sv}"):
        self.log.append(("register application", path))

    @method()
    def UnregisterApplication(self, path: "o"):
        self.log.append(("unregister application", path))


class _AdvertisingManager(ServiceInterface):
    def __init__(self, log: list[tuple[str, str]]) -> None:
        super().__init__("org.bluez.LEAdvertisingManager1")
        self.log = log

    @method()
    def RegisterAdvertisement(self, path: "o", options: "a{sv}"):
        self.log.append(("register advertisement", path))

    @method()
    def UnregisterAdvertisement(self, path: "o"):
        self.log.append(("unregister advertisement", path))

    @dbus_property(access=PropertyAccess.READ)
    def ActiveInstances(self) -> "y":
        return sum(1 if what.startswith("register") else -1 for what, _ in self.log)


class FakeBluez:
    """bluetoothd's D-Bus side on a private bus: ``address`` is what bless should connect to.

    ``adapter=False`` leaves out the adapter object; ``own_name=False`` never
    takes ``org.bluez`` (a bus without bluetoothd).
    """

    def __init__(self, folder: Path, *, adapter: bool = True, own_name: bool = True) -> None:
        assert DAEMON is not None
        config = folder / "bus.conf"
        config.write_text(_CONFIG.format(path=folder / "bus"))
        self._daemon = subprocess.Popen(
            [DAEMON, "--nofork", f"--config-file={config}", "--print-address=1"],
            stdout=subprocess.PIPE,
            stderr=subprocess.DEVNULL,
        )
        assert self._daemon.stdout is not None
        self.address = self._daemon.stdout.readline().decode().strip()
        self.log: list[tuple[str, str]] = []
        self.senders: dict[str, str] = {}
        self.signals: list[tuple[str, str, dict[str, Any]]] = []
        self.adapter = _Adapter()
        self._loop = asyncio.new_event_loop()
        self._thread = threading.Thread(target=self._loop.run_forever, daemon=True)
        self._thread.start()
        self.bus: MessageBus = self.run(self._connect(adapter=adapter, own_name=own_name))

    async def _connect(self, *, adapter: bool, own_name: bool) -> MessageBus:
        bus = await MessageBus(bus_address=self.address).connect()
        bus.add_message_handler(self._see)
        bus.export("/", _Root())
        if adapter:
            for interface in (
                self.adapter,
                _GattManager(self.log),
                _AdvertisingManager(self.log),
            ):
                bus.export("/org/bluez/hci0", interface)
        if own_name:
            await bus.request_name("org.bluez")
        rule = f"type='signal',interface='{PROPERTIES}',member='PropertiesChanged'"
        await bus.call(
            Message(
                destination="org.freedesktop.DBus",
                path="/org/freedesktop/DBus",
                interface="org.freedesktop.DBus",
                member="AddMatch",
                signature="s",
                body=[rule],
            )
        )
        return bus

    def _see(self, message: Message) -> None:
        """Note who registered, and every PropertiesChanged signal (never handles a message)."""
        if message.member in ("RegisterApplication", "RegisterAdvertisement"):
            self.senders[message.member] = message.sender
        if message.message_type is MessageType.SIGNAL and message.member == "PropertiesChanged":
            interface, changed, _invalidated = message.body
            values = {name: variant.value for name, variant in changed.items()}
            self.signals.append((message.path, interface, values))

    def run(self, work: Coroutine[Any, Any, T], timeout: float = 10.0) -> T:
        """Run ``work`` on the fake's loop and wait for its result."""
        return asyncio.run_coroutine_threadsafe(work, self._loop).result(timeout)

    def call(self, path: str, interface: str, member: str, signature: str, *body: Any) -> Message:
        """Call ``member`` on the registered application's object at ``path``; the reply."""
        message = Message(
            destination=self.senders["RegisterApplication"],
            path=path,
            interface=interface,
            member=member,
            signature=signature,
            body=list(body),
        )
        reply = self.run(self.bus.call(message))
        assert reply is not None
        return reply

    def objects(self) -> dict[str, dict[str, dict[str, Any]]]:
        """The application's objects, as bluetoothd reads them after RegisterApplication."""
        reply = self.call("/", "org.freedesktop.DBus.ObjectManager", "GetManagedObjects", "")
        return {
            path: {name: {key: v.value for key, v in props.items()} for name, props in ifs.items()}
            for path, ifs in reply.body[0].items()
        }

    def characteristics(self) -> dict[str, str]:
        """Characteristic UUID -> object path."""
        return {
            interfaces[CHARACTERISTIC]["UUID"]: path
            for path, interfaces in self.objects().items()
            if CHARACTERISTIC in interfaces
        }

    def advertisement(self) -> dict[str, Any]:
        """The registered advertisement's properties, as bluetoothd reads them."""
        path = next(path for what, path in self.log if what == "register advertisement")
        reply = self.call(path, PROPERTIES, "GetAll", "s", ADVERTISEMENT)
        return {name: variant.value for name, variant in reply.body[0].items()}

    def write(self, value: bytes) -> int:
        """Write ``value`` to the tag's write characteristic as BlueZ does; the ATT result."""
        from swarmtag.tag.gatt import WRITE_CHAR_UUID

        path = self.characteristics()[WRITE_CHAR_UUID]
        reply = self.call(path, CHARACTERISTIC, "WriteValue", "aya{sv}", value, {})
        if reply.message_type is MessageType.ERROR:
            return att_code(reply.error_name or "", reply.body[0] if reply.body else "")
        return 0

    def close(self) -> None:
        """Leave the bus, stop the loop and the daemon."""
        with contextlib.suppress(Exception):
            self.bus.disconnect()
            self.run(self.bus.wait_for_disconnect(), timeout=2.0)
        self.bus._sock.close()  # dbus-next never closes its socket
        self._loop.call_soon_threadsafe(self._loop.stop)
        self._thread.join(5.0)
        self._loop.close()
        self._daemon.terminate()
        self._daemon.wait(5.0)
        if self._daemon.stdout is not None:
            self._daemon.stdout.close()


@contextlib.contextmanager
def fake_bluez(folder: Path, **options: bool) -> Iterator[FakeBluez]:
    """A ``FakeBluez`` for the duration of a ``with`` block."""
    fake = FakeBluez(folder, **options)
    try:
        yield fake
    finally:
        fake.close()
