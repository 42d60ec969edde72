"""The writer on a real adapter: one authenticated write to one tag over GATT, with bleak.

One write is one connection (``BleakTagWriter.write``):

1. connect to the tag's address (bleak finds it by scanning, up to ``timeout``);
2. read the state characteristic: the tag's marker id and fields now;
3. reserve the writer's next counter in its ``CounterFile``, saved and
   fsynced **before** anything is sent (``swarmtag.tag.counter``);
4. sign with ``WriteSigner`` (the writer's key, the writer id, that counter,
   the marker read in 2) and write the 20 bytes to the write characteristic
   *with response*, so the tag's verdict comes back as the ATT result;
5. read the state characteristic again: the new state, which confirms it.

A refusal comes back as an ATT error code. bleak >= 3.0 raises
``BleakGATTProtocolError`` carrying it on every platform; older bleak on
BlueZ raises ``BleakDBusError`` with the D-Bus error BlueZ makes of it
(``org.bluez.Error.Failed`` "Operation failed with ATT error: 0x81", and the
named errors of BlueZ's ``create_gatt_dbus_error``, as bleak's own
``assert_gatt_reply`` reads them). ``att_error_code`` reads both;
``refusal`` turns a tag's code into its ``WriteRejected`` subclass
(``gatt.ATT_ERRORS``) with one line saying what it means and what to do.
Everything else (no adapter, no BlueZ, no device, a timeout) is a
``RadioError`` in one line (``bleak.explain``).
"""

from __future__ import annotations

import asyncio
import logging
import os
import re
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, Final, Protocol

import bleak
from bleak.exc import BleakDBusError, BleakError

from swarmtag.errors import (
    ConfigError,
    ForgedWrite,
    IllegalTransition,
    MalformedWrite,
    PayloadError,
    RadioError,
    ReplayedWrite,
    RoleNotAllowed,
    WriteRejected,
    WriterTableFull,
    WrongTarget,
)
from swarmtag.tag.backends.base import check_adapter, check_address, check_seconds
from swarmtag.tag.backends.bleak import adapter_options, explain
from swarmtag.tag.codec import COMPANY_ID, TagState, decode_manufacturer_data
from swarmtag.tag.counter import CounterFile
from swarmtag.tag.gatt import ATT_ERRORS, STATE_CHAR_UUID, WRITE_CHAR_UUID
from swarmtag.tag.keys import read_writer_key_file
from swarmtag.tag.lifecycle import Change, Role, check_role
from swarmtag.tag.record import MAX_WRITERS
from swarmtag.tag.write import WriteSigner

__all__ = [
    "REFUSALS",
    "BleakTagWriter",
    "WriteOutcome",
    "att_error_code",
    "refusal",
]

_LOG = logging.getLogger(__name__)
_LOG.addHandler(logging.NullHandler())

REFUSALS: Final[dict[int, type[WriteRejected]]] = {code: kind for kind, code in ATT_ERRORS.items()}
"""ATT error code -> the refusal it stands for (the inverse of ``gatt.ATT_ERRORS``)."""
_PROTOCOL_ERROR: type[BleakError] | None = getattr(bleak.exc, "BleakGATTProtocolError", None)
_NOT_FOUND: type[BleakError] | None = getattr(bleak.exc, "BleakDeviceNotFoundError", None)
_NO_CHARACTERISTIC: type[BleakError] | None = getattr(
    bleak.exc, "BleakCharacteristicNotFoundError", None
)
_ATT_IN_TEXT: Final = re.compile(r"ATT error: 0x([0-9a-fA-F]{1,2})\b")
_BLUEZ_NAMED: Final = {
    ("org.bluez.Error.NotPermitted", "Read not permitted"): 0x02,
    ("org.bluez.Error.NotPermitted", "Write not permitted"): 0x03,
    ("org.bluez.Error.NotSupported", None): 0x06,
    ("org.bluez.Error.NotAuthorized", None): 0x08,
    ("org.bluez.Error.InvalidArguments", "Invalid offset"): 0x07,
    ("org.bluez.Error.InvalidArguments", "Invalid Length"): 0x0D,
    ("org.bluez.Error.ImproperlyConfigured", None): 0xFD,
}
"""BlueZ's named D-Bus errors for ATT codes (BlueZ ``create_gatt_dbus_error``)."""
_ATT_NAMES: Final = {
    0x02: "Read Not Permitted",
    0x03: "Write Not Permitted",
    0x06: "Request Not Supported",
    0x07: "Invalid Offset",
    0x08: "Insufficient Authorization",
    0x0D: "Invalid Attribute Value Length",
    0x0E: "Unlikely Error",
    0xFD: "CCCD Improperly Configured",
}


class _ClientLike(Protocol):
    """The part of bleak's ``BleakClient`` the writer uses (tests pass a fake one)."""

    async def connect(self) -> None: ...
    async def disconnect(self) -> None: ...
    async def read_gatt_char(self, char_specifier: str) -> bytearray: ...
    async def write_gatt_char(
        self, char_specifier: str, data: bytes, response: bool | None = None
    ) -> None: ...


@dataclass(frozen=True, slots=True)
class WriteOutcome:
    """An accepted write: where, who, which counter, the state before and after.

    ``confirmed`` is whether the state read back shows every field written
    (False: another writer changed the tag in between, or its firmware is
    wrong; the tag still accepted this write).
    """

    address: str
    writer: int
    role: Role
    counter: int
    before: TagState
    after: TagState
    confirmed: bool


def att_error_code(error: BaseException) -> int | None:
    """The ATT error code a bleak exception carries, or ``None`` if it is no ATT answer."""
    if _PROTOCOL_ERROR is not None and isinstance(error, _PROTOCOL_ERROR):
        code = error.args[0] if error.args else None
        return int(code) if isinstance(code, int) else None
    if not isinstance(error, BleakDBusError):
        return None
    details = error.args[1] if len(error.args) > 1 and isinstance(error.args[1], str) else ""
    if error.dbus_error == "org.bluez.Error.Failed":
        match = _ATT_IN_TEXT.search(details)
        return int(match[1], 16) if match else None
    named = _BLUEZ_NAMED.get((error.dbus_error, details))
    return named if named is not None else _BLUEZ_NAMED.get((error.dbus_error, None))


def _hint(kind: type[WriteRejected], writer: int, before: TagState | None) -> str:
    """What a refusal means for this writer and what to do about it."""
    was = f" (the tag was {before.status.name})" if before is not None else ""
    hints: dict[type[WriteRejected], str] = {
        MalformedWrite: "the tag could not parse the 20 bytes: its firmware and this swarmtag "
        "disagree on the write format (docs/hardware.md)",
        ForgedWrite: "the MAC does not verify: the key file is not derived from the site key "
        f"this tag holds (another site, or a rotated key?), or is not writer {writer}'s (a robot "
        "key signs only for its own writer id; the shared robot key only on tags set to accept "
        "it); a software tag on BlueZ older than 5.66 answers every refusal this way "
        "(docs/hardware.md section 5)",
        ReplayedWrite: f"the tag has already accepted this counter or a higher one from writer "
        f"{writer}: this counter file is behind (lost, copied or shared?); use the writer's own "
        "counter file, or a writer id of its own",
        WrongTarget: "the write named another marker than this tag's: the tag changed its "
        "marker id between the read and the write; try again",
        RoleNotAllowed: "a robot may only change the status; urgency and destination need "
        "the operator key",
        IllegalTransition: "a robot may only lift (AWAITING_PICKUP -> PICKED_UP) or release "
        f"(PICKED_UP -> IDLE) a carrier it lifted itself{was}",
        WriterTableFull: f"the tag already tracks {MAX_WRITERS} writer ids and {writer} is new "
        "to it: use a writer id it knows, or rotate the site key and re-provision the tag",
    }
    return hints.get(kind, kind.__doc__ or kind.__name__)


def refusal(
    error: BaseException,
    *,
    address: str,
    writer: int,
    before: TagState | None = None,
    counter: int | None = None,
) -> WriteRejected | RadioError:
    """The error to raise for ``error`` from a write: a typed refusal, or a ``RadioError``.

    A tag's own ATT codes (``gatt.ATT_ERRORS``) become their ``WriteRejected``
    subclass; any other ATT code means the device is not a swarmtag tag (or
    its firmware is wrong); anything else is the radio's problem, and then
    the write may or may not have reached the tag (``counter``, if given, is
    named as spent).
    """
    code = att_error_code(error)
    kind = REFUSALS.get(code) if code is not None else None
    marker = f"tag {before.marker} at {address}" if before is not None else f"the tag at {address}"
    if kind is not None and code is not None:
        return kind(
            f"{marker} refused the write: ATT error 0x{code:02X} ({kind.__name__}): "
            f"{_hint(kind, writer, before)}"
        )
    if code is not None:
        name = _ATT_NAMES.get(code, "not a swarmtag code")
        return RadioError(
            f"the device at {address} answered ATT error 0x{code:02X} ({name}), which a swarmtag "
            "tag never sends: is it a swarmtag tag, with the firmware of docs/hardware.md?"
        )
    spent = (
        ""
        if counter is None
        else f" (it may or may not have been applied; counter {counter} is spent)"
    )
    return RadioError(f"writing to {address} failed{spent}: {explain(error)}")


class BleakTagWriter:
    """Write to tags as one writer: its id, role and key, and its counter file.

    ``client_factory`` replaces ``bleak.BleakClient`` (called as
    ``client_factory(address, timeout=..., **adapter options)``); tests and
    the hidden loopback path of ``swarmtag tag write`` pass a client wired
    to an in-process tag. Every argument is checked here.
    """

    def __init__(
        self,
        *,
        writer: int,
        role: Role,
        key: bytes,
        counters: CounterFile | str | os.PathLike[str],
        timeout: float = 10.0,
        adapter: str | None = None,
        client_factory: Callable[..., _ClientLike] | None = None,
    ) -> None:
        self._signer = WriteSigner(writer=writer, role=check_role(role), key=key)
        self.counters = counters if isinstance(counters, CounterFile) else CounterFile(counters)
        self.timeout = check_seconds("timeout", timeout, low=0.1, high=600.0)
        self.adapter = check_adapter(adapter)
        if client_factory is not None and not callable(client_factory):
            raise ConfigError(f"client_factory: {client_factory!r} is not callable")
        self._factory: Callable[..., _ClientLike] = client_factory or bleak.BleakClient

    @classmethod
    def from_key_file(
        cls,
        path: str | os.PathLike[str],
        *,
        counters: CounterFile | str | os.PathLike[str],
        writer: int | None = None,
        role: Role | None = None,
        **options: Any,  # noqa: ANN401 - timeout, adapter, client_factory
    ) -> BleakTagWriter:
        """A writer with the role, key and writer id of the writer's key file ``path``.

        A robot key file names its writer id: ``writer``, if given, must be it.
        A role key file (operator, legacy shared robot key) names none:
        ``writer`` is needed then. ``role``, if given, must be the file's role
        (``ConfigError`` otherwise): a robot's machine cannot end up signing as
        an operator by mistake.
        """
        found = read_writer_key_file(path)
        if role is not None and check_role(role) is not found.role:
            raise ConfigError(
                f"role: {check_role(role).name.lower()} does not match the key file {path}, "
                f"which holds the {found.role.name.lower()} key"
            )
        return cls(
            writer=found.writer_id(writer, path),
            role=found.role,
            key=found.key,
            counters=counters,
            **options,
        )

    @property
    def writer(self) -> int:
        """This writer's id (0-65535)."""
        return self._signer.writer

    @property
    def role(self) -> Role:
        """This writer's role, the one its key signs for."""
        return self._signer.role

    def write(self, address: str, change: Change, *, marker: int | None = None) -> WriteOutcome:
        """Apply ``change`` to the tag at ``address``; the outcome, or raise why not.

        ``marker``, if given, is checked against the tag's own marker id before
        anything is signed. Raises a ``WriteRejected`` subclass when the tag
        refuses (its counter is spent), ``RadioError`` when the radio cannot
        reach it, ``ConfigError``/``CounterFileError`` for bad input (nothing sent).
        """
        try:
            asyncio.get_running_loop()
        except RuntimeError:
            return asyncio.run(self.write_async(address, change, marker=marker))
        raise ConfigError("BleakTagWriter.write was called inside an event loop: await write_async")

    async def write_async(
        self, address: str, change: Change, *, marker: int | None = None
    ) -> WriteOutcome:
        """``write`` for code that runs in an asyncio event loop."""
        address = check_address(address)
        if not isinstance(change, Change) or change.empty:
            raise ConfigError("change: give a Change that sets at least one field")
        if marker is not None and (isinstance(marker, bool) or marker not in range(256)):
            raise ConfigError(f"marker: {marker!r} is not a marker id in 0-255")
        self.counters.check()  # refuse an unusable counter file before the radio
        client = self._client(address)
        await self._step(client.connect(), address, "connect to")
        try:
            before = await self._read_state(client, address)
            if marker is not None and before.marker != marker:
                raise ConfigError(
                    f"the tag at {address} is marker {before.marker}, not {marker}: "
                    "nothing was sent"
                )
            counter = self.counters.reserve(self.writer)  # on disk before the write is sent
            self._signer.counter = counter - 1
            message = self._signer.sign(before.marker, change)
            try:
                async with asyncio.timeout(self.timeout):
                    await client.write_gatt_char(WRITE_CHAR_UUID, message, response=True)
            except TimeoutError:
                raise RadioError(
                    f"no answer to the write from {address} within {self.timeout:g} s; it may "
                    f"or may not have been applied (counter {counter} is spent): check with "
                    "'swarmtag tag scan'"
                ) from None
            except (BleakError, OSError) as error:
                raise refusal(
                    error, address=address, writer=self.writer, before=before, counter=counter
                ) from None
            after = await self._read_state(client, address)
        finally:
            await self._disconnect(client, address)
        return WriteOutcome(
            address=address,
            writer=self.writer,
            role=self.role,
            counter=counter,
            before=before,
            after=after,
            confirmed=_shows(after, change, before.marker),
        )

    def _client(self, address: str) -> _ClientLike:
        options = adapter_options(self.adapter, client=True)
        return self._factory(address, timeout=self.timeout, **options)

    async def _step(self, call: Any, address: str, doing: str) -> Any:  # noqa: ANN401 - any await
        """Await one GATT step within the timeout; its failures as one-line ``RadioError``s."""
        try:
            async with asyncio.timeout(self.timeout):
                return await call
        except TimeoutError:
            raise RadioError(
                f"could not {doing} {address} within {self.timeout:g} s: is the tag in range "
                "and advertising? ('swarmtag tag scan' lists the tags in range)"
            ) from None
        except (BleakError, OSError) as error:
            if _NOT_FOUND is not None and isinstance(error, _NOT_FOUND):
                raise RadioError(
                    f"no device {address} found within {self.timeout:g} s: is the tag in range "
                    "and advertising? ('swarmtag tag scan' lists the tags and their addresses)"
                ) from None
            if _NO_CHARACTERISTIC is not None and isinstance(error, _NO_CHARACTERISTIC):
                raise RadioError(
                    f"the device at {address} has no swarmtag GATT service "
                    f"({error.args[0] if error.args else 'characteristic'} not found): "
                    "it is not a swarmtag tag"
                ) from None
            raise RadioError(f"could not {doing} {address}: {explain(error)}") from None

    async def _read_state(self, client: _ClientLike, address: str) -> TagState:
        """The tag's 4 state bytes (urgency, status, destination, marker), decoded."""
        value = await self._step(client.read_gatt_char(STATE_CHAR_UUID), address, "read from")
        try:
            return decode_manufacturer_data({COMPANY_ID: bytes(value)})
        except (PayloadError, TypeError, ValueError):
            raise RadioError(
                f"the device at {address} sent {len(value) if hasattr(value, '__len__') else '?'}"
                " state bytes that are not a swarmtag tag state: is it a swarmtag tag?"
            ) from None

    async def _disconnect(self, client: _ClientLike, address: str) -> None:
        """Disconnect; a failure here is logged, never raised (the write's result stands)."""
        try:
            async with asyncio.timeout(self.timeout):
                await client.disconnect()
        except (BleakError, OSError, TimeoutError) as error:
            _LOG.warning("disconnecting from %s failed: %s", address, explain(error))


def _shows(state: TagState, change: Change, marker: int) -> bool:
    """Whether ``state`` is marker ``marker`` with every field ``change`` sets."""
    return (
        state.marker == marker
        and (change.urgency is None or state.urgency == change.urgency)
        and (change.status is None or state.status == change.status)
        and (change.destination is None or state.destination == change.destination)
    )
