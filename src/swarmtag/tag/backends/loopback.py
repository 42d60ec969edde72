"""A GATT client wired to a tag in this process: the writer's whole path, without a radio.

``LoopbackClient`` has the part of bleak's ``BleakClient`` interface that
``BleakTagWriter`` uses, and answers as a tag's GATT server does: the state
characteristic reads the 4 field bytes of the tag's state; a write to the
write characteristic goes to ``SoftwareTag.write`` (what the software tag of
``swarmtag tag emulate`` does with it), and a refusal is raised as bleak
raises a tag's ATT error: ``BleakGATTProtocolError(code)``
(bleak >= 3.0, every platform), or on older bleak the BlueZ D-Bus error
``BleakDBusError("org.bluez.Error.Failed", ["Operation failed with ATT error:
0x81"])``. Tests drive the writer with it, and the hidden ``--backend
loopback`` of ``swarmtag tag write`` writes to a software tag kept in a
``FileStore`` file.
"""

from __future__ import annotations

from typing import Any

import bleak
from bleak.exc import BleakCharacteristicNotFoundError, BleakDBusError, BleakError

from swarmtag.tag.emulator import SoftwareTag
from swarmtag.tag.gatt import STATE_CHAR_UUID, WRITE_CHAR_UUID

__all__ = ["LoopbackClient", "att_exception"]

_PROTOCOL_ERROR: type[BleakError] | None = getattr(bleak.exc, "BleakGATTProtocolError", None)
_WRITE_NOT_PERMITTED = 0x03


def att_exception(code: int) -> BleakError:
    """The exception the installed bleak raises when a GATT server answers ATT error ``code``."""
    if _PROTOCOL_ERROR is not None:
        return _PROTOCOL_ERROR(code)
    return BleakDBusError(
        "org.bluez.Error.Failed", [f"Operation failed with ATT error: 0x{code:02x}"]
    )


class LoopbackClient:
    """A ``BleakClient`` look-alike connected to ``tag`` instead of a radio.

    ``address`` is what the writer asked for; ``writes`` counts the writes
    that reached the tag (accepted or not).
    """

    def __init__(self, address: str, *, tag: SoftwareTag, **_options: Any) -> None:  # noqa: ANN401
        self.address = address
        self.tag = tag
        self.is_connected = False
        self.writes = 0

    async def connect(self) -> None:
        """Connect (always succeeds: the tag is in this process)."""
        self.is_connected = True

    async def disconnect(self) -> None:
        """Disconnect."""
        self.is_connected = False

    def _check(self, char_specifier: str) -> None:
        if not self.is_connected:
            raise BleakError("Not connected")
        if char_specifier not in (STATE_CHAR_UUID, WRITE_CHAR_UUID):
            raise BleakCharacteristicNotFoundError(char_specifier)

    async def read_gatt_char(self, char_specifier: str) -> bytearray:
        """Read a characteristic: the state's 4 field bytes (the write one is not readable)."""
        self._check(char_specifier)
        if char_specifier != STATE_CHAR_UUID:
            raise att_exception(0x02)  # Read Not Permitted
        return bytearray(self.tag.state_value())

    async def write_gatt_char(
        self, char_specifier: str, data: bytes, response: bool | None = None
    ) -> None:
        """Write the authenticated write; a refusal raises the tag's ATT error, as bleak does."""
        self._check(char_specifier)
        if char_specifier != WRITE_CHAR_UUID or not response:
            raise att_exception(_WRITE_NOT_PERMITTED)  # only "write with response" is served
        self.writes += 1
        outcome = self.tag.write(bytes(data))
        if outcome.att_error is not None:
            raise att_exception(outcome.att_error)
