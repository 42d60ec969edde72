"""Claims: the tag protocol's extension by which a robot reserves a carrier for a while.

A robot that commits to a carrier signs a short-lived **claim** and writes
it to the tag; the tag then says who holds it, so that other robots pass it
over. It is an extension: tags and robots without it ignore it.

**Claim write, format version 2** (20 bytes, the same frame as version 1):

    byte  0      format version (0x02)
    byte  1      flags: bits 0-1 role, 1 (robot); every other bit zero
    bytes 2-3    writer id (uint16, little-endian): the claiming robot
    bytes 4-7    counter (uint32): the writer's one counter sequence, shared
                 with its version-1 writes
    byte  8      target marker id
    byte  9      hold: seconds the claim lasts, 1-255
    bytes 10-11  zero
    bytes 12-19  MAC: HMAC-SHA256(the robot's key, bytes 0-11), first 8 bytes

A tag that knows claims checks it as a version-1 write (length, MAC first,
format, target, counter, writer table) and grants it when the tag is
AWAITING_PICKUP and no other robot holds a live claim; the same robot may
renew its own. Anything else is ``ClaimRefused`` (ATT 0x86); an operator's
claim is ``RoleNotAllowed``. A granted claim ends when its time runs out or
the status changes. The claim lives in RAM: a power cycle clears it, but
the counter it used is persisted like any other. A tag without the
extension refuses version 2 as ``MalformedWrite`` (0x0D): the robot learns
that claims are not supported and carries on without one.

**Claim advertisement**: a tag holding a live claim adds Service Data for
its 128-bit service UUID (AD type 0x21) to its scan response: 4 bytes,
``01`` (the claim data's version), the holder's writer id (uint16,
little-endian) and the whole seconds left (1-255). The advertisement's
manufacturer data (6 bytes) is unchanged, so a robot without the extension
reads the tag as before and ignores the service data.

Golden vectors are in docs/tag-protocol.md and ``tests/tag/test_claim.py``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Final

from swarmtag.errors import ClaimRefused, FieldRangeError, MalformedWrite, RoleNotAllowed
from swarmtag.tag._arguments import as_bytes, check_clock, check_int, check_type
from swarmtag.tag.lifecycle import Role
from swarmtag.tag.status import TagStatus
from swarmtag.tag.write import MAX_COUNTER, WriteSigner, authenticated, mac

__all__ = [
    "CLAIM_DATA_LENGTH",
    "CLAIM_DATA_VERSION",
    "CLAIM_WRITE_VERSION",
    "MAX_HOLD",
    "Claim",
    "ClaimWrite",
    "decode_claim_data",
    "encode_claim_data",
    "grant_claim",
    "sign_claim",
    "verify_claim",
]

CLAIM_WRITE_VERSION: Final = 0x02
"""Byte 0 of a claim write."""
CLAIM_DATA_VERSION: Final = 0x01
"""Byte 0 of the claim's service data."""
CLAIM_DATA_LENGTH: Final = 4
MAX_HOLD: Final = 255
"""Longest claim, seconds (one byte)."""


@dataclass(frozen=True, slots=True)
class ClaimWrite:
    """One claim before signing: which robot, which counter, which tag, for how long."""

    writer: int
    counter: int
    target: int
    hold: int
    """Seconds the claim lasts, 1-255."""

    def __post_init__(self) -> None:
        check_int("writer", self.writer, 0xFFFF)
        check_int("counter", self.counter, MAX_COUNTER)
        check_int("target", self.target, 0xFF)
        check_int("hold", self.hold, MAX_HOLD, low=1)


def _signed(claim: ClaimWrite) -> bytes:
    return (
        bytes((CLAIM_WRITE_VERSION, int(Role.ROBOT)))
        + claim.writer.to_bytes(2, "little")
        + claim.counter.to_bytes(4, "little")
        + bytes((claim.target, claim.hold, 0, 0))
    )


def sign_claim(signer: WriteSigner, target: int, hold: int) -> bytes:
    """The 20 bytes of a claim on tag ``target`` for ``hold`` seconds, with the next counter.

    ``signer`` must be a robot's (its own key signs). A refused argument
    leaves its counter as it was.

    >>> from swarmtag.tag import derive_robot_key
    >>> robot = WriteSigner(writer=7, role=Role.ROBOT, key=derive_robot_key(b"k" * 16, 7))
    >>> sign_claim(robot, 12, 30)[:12].hex()
    '02010700000000000c1e0000'
    """
    if check_type("signer", signer, WriteSigner).role is not Role.ROBOT:
        msg = f"signer: claims are a robot's; writer {signer.writer} is an {signer.role.name}"
        raise FieldRangeError(msg)
    if check_int("counter", signer.counter, MAX_COUNTER, low=-1) == MAX_COUNTER:
        msg = f"counter: writer {signer.writer} has used its last counter ({MAX_COUNTER})"
        raise FieldRangeError(msg)
    claim = ClaimWrite(writer=signer.writer, counter=signer.counter + 1, target=target, hold=hold)
    signed = _signed(claim)
    message = signed + mac(signer.key, signed)
    signer.counter = claim.counter
    return message


def verify_claim(
    message: bytes | bytearray | memoryview, key: bytes, *, shared_robot_key: bool = False
) -> ClaimWrite:
    """Check a claim write's MAC under the site key ``key``, then its format; or raise.

    ``ForgedWrite``/``MalformedWrite`` as for any write (``shared_robot_key``
    as for ``verify``); ``RoleNotAllowed`` for an authentic claim that names
    the operator's role.
    """
    signed, role = authenticated(message, key, shared_robot_key=shared_robot_key)
    version, flags = signed[0], signed[1]
    if version != CLAIM_WRITE_VERSION:
        msg = f"claim format version {version} is not {CLAIM_WRITE_VERSION}"
        raise MalformedWrite(msg)
    if role is not Role.ROBOT:
        raise RoleNotAllowed("a claim is a robot's write; the operator's role may not claim")
    if flags != int(Role.ROBOT):
        raise MalformedWrite(f"claim flags byte 0x{flags:02x} sets bits other than the role")
    hold = signed[9]
    if hold == 0:
        raise MalformedWrite("a claim's hold is 1-255 seconds, got 0")
    if signed[10] or signed[11]:
        raise MalformedWrite("a claim's bytes 10 and 11 are zero")
    return ClaimWrite(
        writer=int.from_bytes(signed[2:4], "little"),
        counter=int.from_bytes(signed[4:8], "little"),
        target=signed[8],
        hold=hold,
    )


@dataclass(frozen=True, slots=True)
class Claim:
    """A live claim as a tag holds and advertises it: its holder and when it ends."""

    holder: int
    until: float
    """The tag's clock (seconds) at which it ends."""

    def seconds_left(self, now: float) -> int:
        """Whole seconds left at ``now`` (rounded up), 0 once it has ended."""
        return max(0, min(MAX_HOLD, math.ceil(self.until - check_clock("now", now))))


def grant_claim(claim: ClaimWrite, *, status: TagStatus, held: Claim | None, now: float) -> Claim:
    """The claim a tag holds after granting ``claim`` at ``now``, or ``ClaimRefused``.

    Granted when the tag awaits a robot and no other robot holds a live
    claim (``held`` ended, or is the same robot's: a renewal).
    """
    now = check_clock("now", now)
    if status is not TagStatus.AWAITING_PICKUP:
        msg = f"the tag is {status.name}, not AWAITING_PICKUP: there is nothing to claim"
        raise ClaimRefused(msg)
    if held is not None and held.holder != claim.writer and held.seconds_left(now) > 0:
        msg = (
            f"robot {held.holder} holds this tag for {held.seconds_left(now)} s more; "
            f"robot {claim.writer}'s claim is refused"
        )
        raise ClaimRefused(msg)
    return Claim(holder=claim.writer, until=now + claim.hold)


def encode_claim_data(claim: Claim, now: float) -> bytes:
    """The 4 bytes of service data a tag advertises for a live claim at ``now``.

    >>> encode_claim_data(Claim(holder=7, until=112.0), now=100.0).hex()
    '0107000c'
    """
    left = claim.seconds_left(now)
    if left == 0:
        msg = "claim: it has ended; a tag advertises no claim data then"
        raise FieldRangeError(msg)
    return bytes((CLAIM_DATA_VERSION,)) + claim.holder.to_bytes(2, "little") + bytes((left,))


def decode_claim_data(data: bytes | bytearray | memoryview, now: float) -> Claim:
    """The claim in a tag's service data, heard at ``now``; ``MalformedWrite`` if not one.

    >>> decode_claim_data(bytes.fromhex("0107000c"), now=100.0)
    Claim(holder=7, until=112.0)
    """
    now = check_clock("now", now)
    raw = as_bytes("claim data", data, MalformedWrite)
    if len(raw) != CLAIM_DATA_LENGTH or raw[0] != CLAIM_DATA_VERSION or raw[3] == 0:
        msg = f"claim data {raw.hex()!r} is not 01 + holder (2 bytes) + seconds left (1-255)"
        raise MalformedWrite(msg)
    return Claim(holder=int.from_bytes(raw[1:3], "little"), until=now + raw[3])
