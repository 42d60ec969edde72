"""The tag's GATT service: UUIDs and ATT error codes, shared by every transport.

The 128-bit UUIDs were generated once at random for this project; they share
a base so a sniffer trace reads as one service. ``WRITE`` takes the 20-byte
authenticated write (write with response, so the writer learns the ATT error
code); ``STATE`` reads and notifies the 4 field bytes of the advertisement.
"""

from __future__ import annotations

from typing import Final

from swarmtag.errors import (
    ClaimRefused,
    ForgedWrite,
    IllegalTransition,
    MalformedWrite,
    ReplayedWrite,
    RoleNotAllowed,
    WriteRejected,
    WriterTableFull,
    WrongTarget,
)

__all__ = ["ATT_ERRORS", "SERVICE_UUID", "STATE_CHAR_UUID", "WRITE_CHAR_UUID"]

SERVICE_UUID: Final = "7d2a0001-5c3e-4b8f-9a61-3e0f2c4b9d17"
WRITE_CHAR_UUID: Final = "7d2a0002-5c3e-4b8f-9a61-3e0f2c4b9d17"
STATE_CHAR_UUID: Final = "7d2a0003-5c3e-4b8f-9a61-3e0f2c4b9d17"

ATT_ERRORS: Final[dict[type[WriteRejected], int]] = {
    error: error.att_error
    for error in (
        MalformedWrite,
        ForgedWrite,
        ReplayedWrite,
        WrongTarget,
        RoleNotAllowed,
        IllegalTransition,
        WriterTableFull,
        ClaimRefused,
    )
}
"""The ATT error code a hardware tag answers for each refusal."""
