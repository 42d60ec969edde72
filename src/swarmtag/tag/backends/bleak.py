"""The robot-side scanner on a real adapter: bleak's ``BleakScanner`` in a background thread.

The scanner runs its own asyncio loop in a daemon thread, so a controller
(synchronous, ticking) only ever calls ``states()``. bleak calls
``detection_callback`` for every advertisement of every device in the room;
the callback hands the manufacturer data to ``ScanFilter`` (via
``Scanner._receive``), which ignores foreign devices and counts malformed
payloads without raising, so one broken tag cannot stop the thread.

Adapter errors (``BleakError``, ``OSError``) are logged and retried up to
``retries`` times with exponential backoff; errors that no retry can fix
(no adapter, BlueZ not running, permission denied) end the scan at once.
Either way ``failure`` then holds a ``RadioError`` whose message says what
is missing and how to get it. ``scanner_factory`` replaces ``BleakScanner``
(tests inject a fake class that raises). ``adapter="hci1"`` picks a BlueZ
adapter (``adapter_options`` says it the way the installed bleak takes it);
the default is the system's first adapter.
"""

from __future__ import annotations

import asyncio
import importlib
import logging
import threading
import time
from collections.abc import Callable
from typing import Any, Protocol

import bleak
from bleak.backends.device import BLEDevice
from bleak.backends.scanner import AdvertisementData
from bleak.exc import BleakDBusError, BleakError

from swarmtag.errors import ConfigError, RadioError
from swarmtag.tag.backends.base import DEFAULT_MAX_AGE, Scanner, check_adapter, check_seconds

__all__ = ["BleakTagScanner", "adapter_options", "explain"]

_LOG = logging.getLogger(__name__)
_LOG.addHandler(logging.NullHandler())  # a library: the application decides what is shown
_TICK = 0.05
"""Seconds between two looks at the stop flag inside the scanner thread."""
_NOT_AVAILABLE: type[BleakError] | None = getattr(
    bleak.exc, "BleakBluetoothNotAvailableError", None
)  # bleak >= 1.0 only
_INSTALL_BLUEZ = "install and start BlueZ (sudo apt install bluez; sudo systemctl start bluetooth)"
_GET_PERMISSION = (
    "run as a user in the 'bluetooth' group (sudo usermod -aG bluetooth $USER, then log in again)"
)


class _BleakScannerLike(Protocol):
    async def start(self) -> None: ...
    async def stop(self) -> None: ...


def explain(error: BaseException) -> str:  # noqa: PLR0911 - one return per cause
    """What an adapter error means for the user, and how to fix it, in one line."""
    reason = getattr(getattr(error, "reason", None), "name", "")
    text = str(error).lower()
    dbus = error.dbus_error if isinstance(error, BleakDBusError) else ""
    if _NOT_AVAILABLE is not None and isinstance(error, _NOT_AVAILABLE):
        if reason == "POWERED_OFF":
            return "the Bluetooth adapter is powered off: bluetoothctl power on"
        if reason.startswith("DENIED"):
            return f"Bluetooth permission denied: {_GET_PERMISSION}"
        return f"no Bluetooth LE adapter available ({error}): plug one in, or {_INSTALL_BLUEZ}"
    if "no bluetooth adapters found" in text:
        return "no Bluetooth adapter found: plug in a BLE adapter and check 'bluetoothctl list'"
    if text.startswith("adapter '") and text.endswith("' not found"):
        return f"no Bluetooth {error}: 'bluetoothctl list' shows the adapters there are"
    if isinstance(error, FileNotFoundError) or dbus.endswith(("ServiceUnknown", "NoServer")):
        return f"BlueZ is not reachable (no D-Bus system bus or bluetoothd): {_INSTALL_BLUEZ}"
    if isinstance(error, PermissionError) or dbus.endswith("AccessDenied"):
        return f"permission denied talking to BlueZ: {_GET_PERMISSION}"
    if dbus.endswith("NotReady"):
        return "the Bluetooth adapter is not ready (powered off?): bluetoothctl power on"
    return f"Bluetooth adapter error: {type(error).__name__}: {error}"


def _permanent(error: BaseException) -> bool:
    """Whether retrying cannot help: nothing to scan with, or not allowed to."""
    if _NOT_AVAILABLE is not None and isinstance(error, _NOT_AVAILABLE):
        return True
    if isinstance(error, FileNotFoundError | PermissionError):
        return True
    dbus = error.dbus_error if isinstance(error, BleakDBusError) else ""
    text = str(error).lower()
    return (
        "no bluetooth adapters found" in text
        or (text.startswith("adapter '") and text.endswith("' not found"))
        or dbus.endswith(("ServiceUnknown", "NoServer", "AccessDenied"))
    )


def adapter_options(adapter: str | None, *, client: bool = False) -> dict[str, Any]:
    """The keyword arguments that make bleak use the BlueZ ``adapter`` (``{}`` for the default).

    bleak >= 3.0 takes ``bluez={"adapter": ...}`` and deprecates the plain
    ``adapter=`` keyword that older versions read; other platforms ignore both.
    """
    if check_adapter(adapter) is None:
        return {}
    try:
        bluez_args = importlib.import_module("bleak.args.bluez")  # bleak >= 1.0 only
    except ImportError:
        return {"adapter": adapter}
    typed = getattr(bluez_args, "BlueZClientArgs" if client else "BlueZScannerArgs", None)
    if "adapter" in getattr(typed, "__annotations__", {}):
        return {"bluez": {"adapter": adapter}}
    return {"adapter": adapter}


class BleakTagScanner(Scanner):
    """Scan with bleak in a background thread; ``stop()`` ends the scan and joins the thread."""

    name = "bleak"

    def __init__(
        self,
        *,
        retries: int = 3,
        backoff: float = 0.5,
        scanning_mode: str = "active",
        adapter: str | None = None,
        scanner_factory: Callable[..., _BleakScannerLike] | None = None,
        join_timeout: float = 10.0,
        max_age: float = DEFAULT_MAX_AGE,
        clock: Callable[[], float] = time.monotonic,
    ) -> None:
        super().__init__(max_age=max_age, clock=clock)
        if isinstance(retries, bool) or not isinstance(retries, int) or not 0 <= retries <= 100:
            raise ConfigError(f"retries: {retries!r} is not an integer in 0-100")
        if scanning_mode not in ("active", "passive"):
            raise ConfigError(f"scanning_mode: {scanning_mode!r} is not 'active' or 'passive'")
        self.retries = retries
        self.backoff = check_seconds("backoff", backoff, high=60.0)
        self.join_timeout = check_seconds("join_timeout", join_timeout, high=600.0)
        self.scanning_mode = scanning_mode
        self.adapter = check_adapter(adapter)
        self._factory: Callable[..., _BleakScannerLike] = scanner_factory or bleak.BleakScanner
        self._stop = threading.Event()
        self._scanning = threading.Event()
        self._thread: threading.Thread | None = None
        self._failure: RadioError | None = None
        self.attempts = 0

    def detection_callback(self, device: BLEDevice, advertisement_data: AdvertisementData) -> None:
        """The callback bleak calls: decode the manufacturer data, hold it if ours; never raises."""
        self._receive(device.address, advertisement_data.manufacturer_data, advertisement_data.rssi)

    @property
    def failure(self) -> RadioError | None:
        """Why scanning gave up, once it has (retries spent, or nothing to scan with)."""
        return self._failure

    @property
    def scanning(self) -> bool:
        """Whether bleak's scanner is started right now."""
        return self._scanning.is_set()

    def start(self) -> None:
        """Start the scanner thread (once; a second call while it runs does nothing)."""
        if self._thread is not None and self._thread.is_alive():
            return
        self._stop.clear()
        self._failure = None
        self.attempts = 0
        self._thread = threading.Thread(target=self._run, name="swarmtag-bleak", daemon=True)
        self._thread.start()

    def stop(self) -> None:
        """Ask the thread to stop bleak's scanner and wait for it (up to ``join_timeout``)."""
        self._stop.set()
        thread, self._thread = self._thread, None
        if thread is not None:
            thread.join(self.join_timeout)
            if thread.is_alive():
                _LOG.warning(
                    "BLE scanner thread still running %.1f s after stop", self.join_timeout
                )

    def _run(self) -> None:
        try:
            asyncio.run(self._main())
        except Exception as error:  # noqa: BLE001 - any crash must become a failure, not vanish
            _LOG.exception("BLE scanner thread failed")
            self._failure = RadioError(f"the BLE scanner stopped: {explain(error)}")

    async def _main(self) -> None:
        """Scan until told to stop, retrying adapter errors with exponential backoff."""
        retried = 0
        while not self._stop.is_set():
            self.attempts += 1
            try:
                await self._scan_once()
            except (BleakError, OSError) as error:
                message = explain(error)
                if _permanent(error) or retried >= self.retries:
                    tries = (
                        f" (gave up after {self.attempts} attempts)" if self.attempts > 1 else ""
                    )
                    _LOG.error("BLE scanning failed: %s%s", message, tries)
                    self._failure = RadioError(message + tries)
                    return
                retried += 1
                pause = self.backoff * 2 ** (retried - 1)
                _LOG.warning(
                    "BLE adapter error: %s; retry %d of %d in %.2f s",
                    message,
                    retried,
                    self.retries,
                    pause,
                )
                await self._sleep(pause)
            else:
                return

    async def _scan_once(self) -> None:
        """One bleak scanner from start to the stop flag."""
        options: dict[str, Any] = {"scanning_mode": self.scanning_mode}
        options.update(adapter_options(self.adapter))
        scanner = self._factory(detection_callback=self.detection_callback, **options)
        await scanner.start()
        self._scanning.set()
        try:
            while not self._stop.is_set():
                await asyncio.sleep(_TICK)
        finally:
            self._scanning.clear()
            try:
                await scanner.stop()
            except (BleakError, OSError) as error:
                _LOG.warning("stopping the BLE scanner failed: %s", explain(error))

    async def _sleep(self, seconds: float) -> None:
        """Sleep ``seconds`` or until the stop flag is set, whichever comes first."""
        deadline = time.monotonic() + seconds
        while not self._stop.is_set() and (left := deadline - time.monotonic()) > 0:
            await asyncio.sleep(min(_TICK, left))
