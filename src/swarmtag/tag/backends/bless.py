"""The software tag on a real adapter: bless's GATT server on BlueZ, in a background thread.

``BlessTagServer`` serves a ``SoftwareTag`` the way the nRF52833 firmware
does (docs/hardware.md): the primary service ``SERVICE_UUID`` with ``WRITE``
(write with response, the 20-byte authenticated write) and ``STATE`` (read
and notify, the 4 field bytes), and an advertisement that carries the
service UUID and the 6-byte manufacturer-specific payload. It runs bless's
BlueZ server in its own asyncio loop in a daemon thread, so the command line
only starts it, reads ``outcomes()`` and stops it.

What bless 0.3 does not do, and how it is done here, through bless's own
BlueZ objects:

- *Manufacturer data in the advertisement.* bless advertises only a name
  and the first service UUID. The advertisement here is bless's own
  ``BlueZLEAdvertisement`` with its ``ManufacturerData`` property set
  before it is registered with BlueZ's ``LEAdvertisingManager1``; after an
  accepted write the property is changed and ``PropertiesChanged`` is
  emitted, which BlueZ (5.47 and later) turns into a refreshed
  advertisement. 3 bytes of flags, 18 of service UUID and 8 of
  manufacturer data fit the 31 bytes of a legacy advertisement; the name
  goes into the scan response.
- *ATT error codes.* bless hands a write to ``write_request`` and answers
  "success" when it returns. A refusal raises a D-Bus error instead, which
  BlueZ turns into the ATT error of the write response: the name
  ``org.bluez.Error.InvalidValueLength`` is ATT 0x0D on every BlueZ, and
  ``org.bluez.Error.Failed`` with the message ``"0x81"`` is ATT 0x81 from
  BlueZ 5.66 on (older BlueZ answers 0x80 for every ``Failed``).

Only Linux with BlueZ: bless's macOS and Windows servers cannot advertise
manufacturer data. Errors that leave no radio to serve with (no D-Bus system
bus, no bluetoothd, no adapter, no permission) are a ``RadioError`` in
``failure`` whose message says what is missing and how to get it.
"""

from __future__ import annotations

import asyncio
import contextlib
import errno
import logging
import os
import sys
import threading
from collections.abc import Callable
from pathlib import Path
from typing import Any, Final
from urllib.parse import unquote
from uuid import UUID

from swarmtag._checks import check_int
from swarmtag.errors import ConfigError, RadioError
from swarmtag.tag.backends.base import check_adapter, check_seconds
from swarmtag.tag.backends.server import TagServer
from swarmtag.tag.codec import COMPANY_ID
from swarmtag.tag.emulator import SoftwareTag
from swarmtag.tag.gatt import SERVICE_UUID, STATE_CHAR_UUID, WRITE_CHAR_UUID

NEEDS_EXTRA: Final = (
    "the software tag needs the bless package, which is not installed: "
    "pip install 'swarmtag[tag-emulator]'"
)
LINUX_ONLY: Final = (
    "the software tag needs Linux with BlueZ: bless's macOS and Windows servers "
    "cannot put manufacturer data into the advertisement"
)

if sys.platform != "linux":
    raise RadioError(LINUX_ONLY)

try:
    from bleak.exc import BleakDBusError
    from bless.backends.attribute import GATTAttributePermissions
    from bless.backends.bluezdbus.dbus.advertisement import BlueZLEAdvertisement, Type
    from bless.backends.bluezdbus.server import BlessServerBlueZDBus
    from bless.backends.characteristic import GATTCharacteristicProperties
    from dbus_next.errors import DBusError
    from dbus_next.signature import Variant

    from swarmtag.tag.backends.bleak import explain
except ImportError as missing:
    if (missing.name or "").split(".")[0] not in ("bless", "dbus_next", "bleak"):
        raise
    raise ConfigError(NEEDS_EXTRA) from None

__all__ = [
    "ADVERTISING_MANAGER",
    "LINUX_ONLY",
    "NEEDS_EXTRA",
    "BlessTagServer",
    "dbus_error",
    "explain_server_error",
]

_LOG = logging.getLogger(__name__)
_LOG.addHandler(logging.NullHandler())  # a library: the application decides what is shown
_TICK: Final = 0.05
"""Seconds between two looks at the stop flag inside the server thread."""
_CLOSE_TIMEOUT: Final = 2.0
"""Seconds to wait for the D-Bus connection to close after leaving the bus."""
_SYSTEM_BUS: Final = "unix:path=/var/run/dbus/system_bus_socket"
"""The system bus's address where ``DBUS_SYSTEM_BUS_ADDRESS`` is not set (D-Bus specification)."""
ADVERTISING_MANAGER: Final = "org.bluez.LEAdvertisingManager1"
"""BlueZ's interface for registering advertisements (on the adapter object)."""
_FAILED: Final = "org.bluez.Error.Failed"
_INVALID_LENGTH: Final = "org.bluez.Error.InvalidValueLength"
_NOT_PERMITTED: Final = "org.bluez.Error.NotPermitted"
_IO_ERROR: Final = "org.freedesktop.DBus.Error.IOError"  # BlueZ: ATT 0x0E, unlikely error
_INVALID_LENGTH_CODE: Final = 0x0D
_APPLICATION_CODES: Final = range(0x80, 0xA0)


def _error(name: str, text: str) -> DBusError:
    """A D-Bus error reply ``name`` with ``text`` (dbus-next's constructor is untyped)."""
    return DBusError(name, text)  # type: ignore[no-untyped-call]


def _set_property(interface: object, name: str, value: object) -> None:
    """Set a D-Bus property of one of bless's interface objects (its Python setter)."""
    setattr(interface, name, value)


def dbus_error(att_error: int) -> DBusError:
    """The D-Bus error a write callback raises so that BlueZ answers ATT ``att_error``.

    0x0D is ``org.bluez.Error.InvalidValueLength``; an application code
    0x80-0x9F is ``org.bluez.Error.Failed`` with the code as its message
    (``"0x81"``), which BlueZ 5.66 and later parse into the ATT error.
    """
    att_error = check_int("att_error", att_error, low=0, high=0xFF)
    if att_error == _INVALID_LENGTH_CODE:
        return _error(_INVALID_LENGTH, "0x0d")
    if att_error not in _APPLICATION_CODES:
        msg = f"att_error: 0x{att_error:02x} is neither 0x0d nor an application code 0x80-0x9f"
        raise ConfigError(msg)
    return _error(_FAILED, f"0x{att_error:02x}")


def explain_server_error(error: BaseException) -> str:
    """What an error starting or running the GATT server means, and how to fix it, in one line."""
    if isinstance(error, DBusError):
        if error.type.endswith("NotPermitted") and "advertisement" in str(error.text).lower():
            return (
                f"the adapter cannot take another advertisement ({error.text}): stop other "
                "advertising programs, or use another adapter"
            )
        return explain(BleakDBusError(error.type, [error.text]))
    if isinstance(error, ConnectionRefusedError):
        return explain(FileNotFoundError(str(error)))  # a socket without a bus behind it
    if "no adapter named" in str(error).lower():
        return (
            f"no Bluetooth adapter found ({error}): plug in a BLE adapter and check "
            "'bluetoothctl list'"
        )
    return explain(error)


class _RepliedErrors(logging.Filter):
    """Drop dbus-next's log of a ``DBusError`` it has already answered with an error reply.

    dbus-next 0.2.3 sends the error reply of a method that raises
    ``DBusError`` and then lets the error escape its ``SendReply.__exit__``
    anyway, so it also logs "got unexpected error processing a message" with
    a traceback, on the root logger, for every refused write. The reply went
    out; the log is noise. Installed on the root logger only while serving.
    """

    def filter(self, record: logging.LogRecord) -> bool:
        """Keep every record but dbus-next's duplicate of an answered ``DBusError``."""
        source = record.pathname.replace("\\", "/")
        return not (
            source.endswith("dbus_next/message_bus.py")
            and "dbus_next.errors.DBusError: " in record.getMessage()
        )


_REPLIED_ERRORS: Final = _RepliedErrors()
_quieted = {"servers": 0}
_quieting = threading.Lock()


def _quiet(*, on: bool) -> None:
    """Install the filter while any server runs; remove it when the last one stops."""
    with _quieting:
        _quieted["servers"] += 1 if on else -1
        if _quieted["servers"] > 0:
            logging.getLogger().addFilter(_REPLIED_ERRORS)
        else:
            _quieted["servers"] = 0
            logging.getLogger().removeFilter(_REPLIED_ERRORS)


def _check_system_bus() -> None:
    """Refuse at once a system bus whose socket files are all missing (no bluetoothd).

    dbus-next leaves the socket of a failed connection open; asking the
    file system first keeps the common case (no D-Bus, no BlueZ) clean.
    The address is read as the D-Bus specification writes it (and dbus-next
    reads it): ``transport:key=value,...`` entries separated by ``;``, the
    values %-escaped. Only an address of ``unix`` sockets alone is judged here;
    any other (or one that does not parse) is left to ``connect()``.
    """
    address = os.environ.get("DBUS_SYSTEM_BUS_ADDRESS", _SYSTEM_BUS)
    entries = [entry.partition(":") for entry in address.split(";") if entry]
    if not entries or any(transport != "unix" or not colon for transport, colon, _ in entries):
        return
    paths = [_address_option(options, "path") for _, _, options in entries]
    if not any(path and Path(path).exists() for path in paths):
        raise FileNotFoundError(errno.ENOENT, "no D-Bus system bus socket", paths[0])


def _address_option(options: str, key: str) -> str | None:
    """The unescaped value of ``key`` among a D-Bus address entry's ``key=value,...``."""
    for option in options.split(","):
        name, equals, value = option.partition("=")
        if name == key and equals:
            return unquote(value)
    return None


async def _leave(bus: Any) -> None:  # noqa: ANN401 - dbus-next's MessageBus
    """Disconnect from the bus and close the socket (dbus-next 0.2.3 never closes it)."""
    if bus.connected:
        bus.disconnect()
        with contextlib.suppress(Exception):  # the bus may have gone already: nothing to wait for
            await asyncio.wait_for(bus.wait_for_disconnect(), timeout=_CLOSE_TIMEOUT)
    sock = getattr(bus, "_sock", None)
    if sock is not None:
        sock.close()


def _same_uuid(uuid: object, expected: str) -> bool:
    try:
        return UUID(str(uuid)) == UUID(expected)
    except ValueError:
        return False


class BlessTagServer(TagServer):
    """Serve a software tag over BLE with bless on BlueZ; ``stop()`` ends it and joins the thread.

    ``local_name`` is the name in the scan response (and, as bless does it,
    the adapter's alias while serving); ``adapter`` picks one (``"hci1"``),
    by default BlueZ's first. ``server_factory`` replaces bless's ``BlessServerBlueZDBus``.
    """

    name = "bless"

    def __init__(
        self,
        tag: SoftwareTag,
        *,
        local_name: str | None = None,
        adapter: str | None = None,
        start_timeout: float = 20.0,
        join_timeout: float = 10.0,
        server_factory: Callable[..., Any] | None = None,
    ) -> None:
        super().__init__(tag)
        self.local_name = local_name or f"swarmtag-{tag.state.marker}"
        if not isinstance(self.local_name, str) or not self.local_name.isprintable():
            raise ConfigError(f"local_name: {local_name!r} is not a printable name")
        self.adapter = check_adapter(adapter)
        self.start_timeout = check_seconds("start_timeout", start_timeout, low=0.1, high=600.0)
        self.join_timeout = check_seconds("join_timeout", join_timeout, high=600.0)
        self._factory: Callable[..., Any] = server_factory or BlessServerBlueZDBus
        self._server: Any = None
        self._advertisement: BlueZLEAdvertisement | None = None
        self._registered = {"application": False, "advertisement": False}
        self._stop = threading.Event()
        self._ready = threading.Event()
        self._thread: threading.Thread | None = None

    # --- the callbacks bless calls (in the server's loop thread) ---------------------------

    def read_request(self, characteristic: Any, **_options: object) -> bytearray:  # noqa: ANN401 - bless's characteristic
        """Read callback (bless): ``STATE`` reads the 4 field bytes; nothing else is readable."""
        if _same_uuid(getattr(characteristic, "uuid", None), STATE_CHAR_UUID):
            return bytearray(self.tag.state_value())
        raise _error(_NOT_PERMITTED, "only the state characteristic can be read")

    def write_request(self, characteristic: Any, value: Any, **_options: object) -> None:  # noqa: ANN401 - bless's
        """Write callback (bless): apply the write, or raise the D-Bus error of its ATT code.

        After an accepted write the ``STATE`` value is updated (BlueZ notifies
        subscribers) and the advertisement refreshed; a refused write changes
        nothing and answers its ATT error.
        """
        if not _same_uuid(getattr(characteristic, "uuid", None), WRITE_CHAR_UUID):
            raise _error(_NOT_PERMITTED, "only the write characteristic can be written")
        outcome = self._serve_write(bytes(value))
        if outcome is None:  # the store failed: the write is not acted on, the server stops
            raise _error(_IO_ERROR, "the tag could not save its state")
        if outcome.att_error is not None:
            raise dbus_error(outcome.att_error)
        self._publish()

    def _manufacturer_data(self) -> dict[int, Variant]:
        """The advertisement's ``ManufacturerData`` (D-Bus ``a{qv}``): ``{0xFFFF: 4 bytes}``."""
        return {COMPANY_ID: Variant("ay", self.tag.state_value())}

    def _publish(self) -> None:
        """Show the tag's state: ``STATE`` value and notification, then the advertisement."""
        server = self._server
        if server is None:
            return
        server.get_characteristic(STATE_CHAR_UUID).value = bytearray(self.tag.state_value())
        server.update_value(SERVICE_UUID, STATE_CHAR_UUID)  # sets Value: BlueZ notifies
        advertisement = self._advertisement
        if advertisement is not None:
            data = self._manufacturer_data()
            _set_property(advertisement, "ManufacturerData", data)
            advertisement.emit_properties_changed({"ManufacturerData": data})

    # --- serving: open and close in the server's loop ---------------------------------------

    async def open(self, loop: asyncio.AbstractEventLoop) -> None:
        """Build the GATT service on bless's server, register it and start advertising."""
        if self._factory is BlessServerBlueZDBus:
            _check_system_bus()
        server = self._factory(name=self.local_name, loop=loop, adapter=self.adapter)
        self._server = server
        server.read_request_func = self.read_request
        server.write_request_func = self.write_request
        await server.add_new_service(SERVICE_UUID)
        await server.add_new_characteristic(
            SERVICE_UUID,
            WRITE_CHAR_UUID,
            GATTCharacteristicProperties.write,
            None,
            GATTAttributePermissions.writeable,
        )
        await server.add_new_characteristic(
            SERVICE_UUID,
            STATE_CHAR_UUID,
            GATTCharacteristicProperties.read | GATTCharacteristicProperties.notify,
            bytearray(self.tag.state_value()),
            GATTAttributePermissions.readable,
        )
        app = server.app
        server.bus.export(app.path, app)
        await app.register(server.adapter)  # GattManager1.RegisterApplication
        self._registered["application"] = True
        await app.set_name(server.adapter, self.local_name)
        advertisement = BlueZLEAdvertisement(Type.PERIPHERAL, len(app.advertisements) + 1, app)
        _set_property(advertisement, "ServiceUUIDs", [SERVICE_UUID])
        _set_property(advertisement, "ManufacturerData", self._manufacturer_data())
        app.advertisements.append(advertisement)
        server.bus.export(advertisement.path, advertisement)
        self._advertisement = advertisement
        manager = server.adapter.get_interface(ADVERTISING_MANAGER)
        await manager.call_register_advertisement(advertisement.path, {})
        self._registered["advertisement"] = True

    async def close(self) -> None:
        """Stop advertising, unregister the service and leave the bus; logs what fails."""
        server, self._server = self._server, None
        if server is None or not hasattr(server, "bus"):
            return
        steps: list[tuple[str, Callable[[], Any]]] = []
        if self._registered["advertisement"]:
            steps.append(("stop advertising", lambda: server.app.stop_advertising(server.adapter)))
        if self._registered["application"]:
            steps.append(("unregister the service", lambda: server.app.unregister(server.adapter)))
        for doing, step in steps:
            try:
                await step()
            except (DBusError, OSError) as error:
                _LOG.warning("the software tag could not %s: %s", doing, error)
        self._registered = {"application": False, "advertisement": False}
        self._advertisement = None
        await _leave(server.bus)

    # --- the thread ---------------------------------------------------------------------------

    @property
    def bless_server(self) -> Any:  # noqa: ANN401 - bless's BlessServerBlueZDBus
        """The bless server object while the tag is open (``None`` before and after)."""
        return self._server

    @property
    def serving(self) -> bool:
        """Whether the tag is registered with BlueZ and advertising right now."""
        return self._registered["advertisement"] and self._thread is not None

    def start(self) -> None:
        """Start the server thread and wait until it advertises or fails (``start_timeout``)."""
        if self._thread is not None and self._thread.is_alive():
            return
        self._stop.clear()
        self._ready.clear()
        self._failure = None
        _quiet(on=True)
        self._thread = threading.Thread(target=self._run, name="swarmtag-bless", daemon=True)
        self._thread.start()
        if not self._ready.wait(self.start_timeout) and self._failure is None:
            self._failure = RadioError(
                f"BlueZ did not register the software tag within {self.start_timeout:g} s: "
                "check 'systemctl status bluetooth' and 'bluetoothctl show'"
            )
            self._stop.set()

    def stop(self) -> None:
        """Stop advertising, unregister from BlueZ and join the thread (up to ``join_timeout``)."""
        self._stop.set()
        thread, self._thread = self._thread, None
        if thread is None:
            return
        thread.join(self.join_timeout)
        if thread.is_alive():
            _LOG.warning("software tag thread still running %.1f s after stop", self.join_timeout)
        else:
            _quiet(on=False)

    def _run(self) -> None:
        try:
            asyncio.run(self._main())
        except Exception as error:  # noqa: BLE001 - any crash must become a failure, not vanish
            _LOG.exception("software tag thread failed")
            self._failure = RadioError(f"the software tag stopped: {explain_server_error(error)}")
        finally:
            self._ready.set()

    async def _main(self) -> None:
        """Open the server, serve until told to stop (or the store fails), then close it."""
        try:
            try:
                await self.open(asyncio.get_running_loop())
            except Exception as error:  # noqa: BLE001 - bless raises bare Exception for no adapter
                self._failure = RadioError(explain_server_error(error))
                return
            finally:
                self._ready.set()
            while not self._stop.is_set() and self._failure is None:
                await asyncio.sleep(_TICK)
        finally:
            await self.close()
