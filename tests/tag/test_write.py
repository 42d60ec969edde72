"""The 20-byte authenticated write format (SPEC §2.3)."""

from __future__ import annotations

import hashlib
import hmac

import pytest
from hypothesis import given
from hypothesis import strategies as st

from swarmtag.errors import FieldRangeError, ForgedWrite, MalformedWrite
from swarmtag.tag import WRITE_LENGTH, Change, Role, TagStatus, Write, WriteSigner, sign, verify
from tests.strategies import changes

KEY = b"0123456789abcdef"  # 16-byte site key


def _mac(signed: bytes) -> bytes:
    return hmac.new(KEY, signed, hashlib.sha256).digest()[:8]


# A robot (writer 7) lifts tag 12 with counter 1, written out byte by byte.
ROBOT_LIFT_SIGNED = bytes(
    [
        0x01,  # format version
        0x21,  # flags: role 1 (robot) | status present (0x20)
        0x07, 0x00,  # writer id 7, little-endian
        0x01, 0x00, 0x00, 0x00,  # counter 1, little-endian
        0x0C,  # target marker 12
        0x00,  # urgency (absent)
        0x02,  # status PICKED_UP
        0x00,  # destination (absent)
    ]
)  # fmt: skip
# An operator (writer 0x0102) sets urgency 9 and destination 3 on tag 5, counter 0x0A0B0C0D.
OPERATOR_SIGNED = bytes([0x01, 0x52, 0x02, 0x01, 0x0D, 0x0C, 0x0B, 0x0A, 0x05, 0x09, 0x00, 0x03])


def test_golden_robot_write():
    write = Write(
        writer=7, role=Role.ROBOT, counter=1, target=12, change=Change(status=TagStatus.PICKED_UP)
    )
    message = sign(write, KEY)
    assert message == ROBOT_LIFT_SIGNED + _mac(ROBOT_LIFT_SIGNED)
    assert len(message) == 20 == WRITE_LENGTH
    assert verify(message, KEY) == write


def test_golden_operator_write():
    write = Write(
        writer=0x0102,
        role=Role.OPERATOR,
        counter=0x0A0B0C0D,
        target=5,
        change=Change(urgency=9, destination=3),
    )
    assert sign(write, KEY) == OPERATOR_SIGNED + _mac(OPERATOR_SIGNED)
    assert verify(OPERATOR_SIGNED + _mac(OPERATOR_SIGNED), KEY) == write


@given(
    writer=st.integers(0, 0xFFFF),
    role=st.sampled_from(Role),
    counter=st.integers(0, 0xFFFF_FFFF),
    target=st.integers(0, 255),
    change=changes,
)
def test_sign_verify_round_trip(writer, role, counter, target, change):
    write = Write(writer=writer, role=role, counter=counter, target=target, change=change)
    message = sign(write, KEY)
    assert len(message) <= 20
    assert verify(message, KEY) == write


def test_wrong_key_is_forged():
    message = sign(
        Write(writer=1, role=Role.OPERATOR, counter=0, target=1, change=Change(urgency=1)), KEY
    )
    with pytest.raises(ForgedWrite):
        verify(message, b"another-site-key")


@pytest.mark.parametrize("position", range(20))
def test_any_flipped_byte_is_forged(position):
    message = bytearray(ROBOT_LIFT_SIGNED + _mac(ROBOT_LIFT_SIGNED))
    message[position] ^= 0x01
    with pytest.raises(ForgedWrite):
        verify(bytes(message), KEY)


@pytest.mark.parametrize("length", [0, 12, 19, 21, 40])
def test_wrong_length_is_malformed(length):
    with pytest.raises(MalformedWrite, match="20 bytes"):
        verify(bytes(length), KEY)


@pytest.mark.parametrize(
    ("signed", "words"),
    [
        (bytes([0x02, 0x21, 7, 0, 1, 0, 0, 0, 12, 0, 2, 0]), "version 2"),
        (bytes([0x01, 0x20, 7, 0, 1, 0, 0, 0, 12, 0, 2, 0]), "role 0"),
        (bytes([0x01, 0x23, 7, 0, 1, 0, 0, 0, 12, 0, 2, 0]), "role 3"),
        (bytes([0x01, 0xA1, 7, 0, 1, 0, 0, 0, 12, 0, 2, 0]), "reserved bits"),
        (bytes([0x01, 0x29, 7, 0, 1, 0, 0, 0, 12, 0, 2, 0]), "reserved bits"),
        (bytes([0x01, 0x21, 7, 0, 1, 0, 0, 0, 12, 5, 2, 0]), "urgency byte is 5"),
        (bytes([0x01, 0x21, 7, 0, 1, 0, 0, 0, 12, 0, 2, 4]), "destination byte is 4"),
        (bytes([0x01, 0x12, 7, 0, 1, 0, 0, 0, 12, 10, 0, 0]), "urgency 10"),
        (bytes([0x01, 0x21, 7, 0, 1, 0, 0, 0, 12, 0, 3, 0]), "status byte 0x03"),
        (bytes([0x01, 0x01, 7, 0, 1, 0, 0, 0, 12, 0, 0, 0]), "at least one field"),
        (bytes([0x01, 0x02, 7, 0, 1, 0, 0, 0, 12, 0, 9, 0]), "status byte is 9"),
    ],
)
def test_authentic_but_malformed_writes(signed, words):
    with pytest.raises(MalformedWrite, match=words):
        verify(signed + _mac(signed), KEY)


@pytest.mark.parametrize(
    ("fields", "name"),
    [
        ({"writer": 0x10000}, "writer"),
        ({"counter": -1}, "counter"),
        ({"counter": 2**32}, "counter"),
        ({"target": 256}, "target"),
        ({"change": Change()}, "change"),
        ({"change": Change(urgency=10)}, "urgency"),
        ({"change": Change(destination=-1)}, "destination"),
    ],
)
def test_write_fields_validated(fields, name):
    base = {
        "writer": 1,
        "role": Role.OPERATOR,
        "counter": 0,
        "target": 0,
        "change": Change(urgency=1),
    }
    with pytest.raises(FieldRangeError, match=name):
        Write(**{**base, **fields})


@pytest.mark.parametrize("key", [b"", b"short", b"x" * 15, "a text key of 16+"])
def test_short_or_non_bytes_keys_refused(key):
    write = Write(writer=1, role=Role.OPERATOR, counter=0, target=0, change=Change(urgency=1))
    with pytest.raises(FieldRangeError, match="site_key"):
        sign(write, key)


def test_signer_counts_up_from_zero_and_keeps_its_counter():
    signer = WriteSigner(writer=4, role=Role.ROBOT, key=KEY)
    first = verify(signer.sign(3, Change(status=TagStatus.PICKED_UP)), KEY)
    second = verify(signer.sign(3, Change(status=TagStatus.IDLE)), KEY)
    assert (first.counter, second.counter, signer.counter) == (0, 1, 1)
    resumed = WriteSigner(writer=4, role=Role.ROBOT, key=KEY, counter=signer.counter)
    assert verify(resumed.sign(3, Change(status=TagStatus.IDLE)), KEY).counter == 2
