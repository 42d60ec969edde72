"""The 20-byte authenticated write format (SPEC §2.3), signed with writer keys.

Every expected byte string below is computed *outside* swarmtag: the robot
and role keys by ``_hkdf_rfc5869`` (a transcription of RFC 5869 §2.2-2.3, checked
against the RFC's own test vectors in ``test_independent_hkdf_matches_rfc_5869``)
and the MACs by ``hmac.new(role_key, signed, sha256).digest()[:8]``. The
literal hex values were printed once from those two functions and pinned, so
a change of derivation or MAC shows up even if both sides changed together.
"""

from __future__ import annotations

import hashlib
import hmac

import pytest
from hypothesis import given
from hypothesis import strategies as st

from swarmtag.errors import FieldRangeError, ForgedWrite, MalformedWrite
from swarmtag.tag import (
    WRITE_LENGTH,
    Change,
    Role,
    TagStatus,
    Write,
    WriteSigner,
    derive_robot_key,
    derive_role_key,
    sign,
    verify,
)
from tests.strategies import changes

KEY = b"0123456789abcdef"  # 16-byte site key: what a tag holds


def _hkdf_rfc5869(ikm: bytes, salt: bytes, info: bytes, length: int) -> bytes:
    """HKDF-SHA256 written from RFC 5869, independent of swarmtag.tag.keys."""
    prk = hmac.new(salt, ikm, hashlib.sha256).digest()  # 2.2 extract
    okm, block = b"", b""
    for i in range(1, 256):  # 2.3 expand: T(i) = HMAC(PRK, T(i-1) | info | i)
        if len(okm) >= length:
            break
        block = hmac.new(prk, block + info + bytes([i]), hashlib.sha256).digest()
        okm += block
    return okm[:length]


# RFC 5869 Appendix A, test cases 1-3 (SHA-256): IKM, salt, info, L, OKM.
RFC_5869_CASES = [
    (
        bytes([0x0B] * 22),
        bytes(range(0x0D)),
        bytes(range(0xF0, 0xFA)),
        42,
        "3cb25f25faacd57a90434f64d0362f2a2d2d0a90cf1a5a4c5db02d56ecc4c5bf34007208d5b887185865",
    ),
    (
        bytes(range(0x50)),
        bytes(range(0x60, 0xB0)),
        bytes(range(0xB0, 0x100)),
        82,
        (
            "b11e398dc80327a1c8e7f78c596a49344f012eda2d4efad8a050cc4c19afa97c"
            "59045a99cac7827271cb41c65e590e09da3275600c2f09b8367793a9aca3db71"
            "cc30c58179ec3e87c14c01d5c1f3434f1d87"
        ),
    ),
    (
        bytes([0x0B] * 22),
        b"",
        b"",
        42,
        "8da4e775a563c18f715f802a063c5a31b8a11f5c5ee1879ec3454e5f3c738d2d9d201395faa4b61a96c8",
    ),
]

# The derivation parameters, as docs/hardware.md states them for the firmware.
SALT = b"swarmtag hkdf salt v1"
INFO = {
    Role.ROBOT: b"swarmtag write key v1 robot",  # the legacy shared robot key
    Role.OPERATOR: b"swarmtag write key v1 operator",
}
ROBOT_INFO = b"swarmtag writer key v1 robot"  # + the writer id, uint16 little-endian
# _hkdf_rfc5869(KEY, SALT, INFO[role], 32), printed once and pinned:
ROBOT_KEY = bytes.fromhex("adccd32da6e599542c68b7c6666b6039b2a4a651864f9a9938e9e4f18858edd3")
OPERATOR_KEY = bytes.fromhex("4d047418604c21257e0b562d3a705e382c6c27efbbdfc1f616a34b080d865b1b")
ROLE_KEYS = {Role.ROBOT: ROBOT_KEY, Role.OPERATOR: OPERATOR_KEY}
# _hkdf_rfc5869(KEY, SALT, ROBOT_INFO + bytes([7, 0]), 32), printed once and pinned:
ROBOT7_KEY = bytes.fromhex("b896d9da3aec6f70a272c3ee2143f916e43fdb13593237feae8e62738c257db9")


def _robot_key(writer: int) -> bytes:
    """Robot ``writer``'s key, computed here independently of swarmtag."""
    return _hkdf_rfc5869(KEY, SALT, ROBOT_INFO + writer.to_bytes(2, "little"), 32)


def _key_of(signed: bytes) -> bytes:
    """The key a tag checks ``signed`` under: the robot's own, or the operator key."""
    role = Role(signed[1] & 0x03)
    return _robot_key(int.from_bytes(signed[2:4], "little")) if role is Role.ROBOT else OPERATOR_KEY


def _mac(signed: bytes, role_key: bytes = ROBOT_KEY) -> bytes:
    return hmac.new(role_key, signed, hashlib.sha256).digest()[:8]


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
# ROBOT_LIFT_SIGNED + _mac(ROBOT_LIFT_SIGNED, ROBOT7_KEY), printed once and pinned:
ROBOT_LIFT = bytes.fromhex("01210700010000000c0002004edbe4fb3b1c5433")
# ROBOT_LIFT_SIGNED + _mac(ROBOT_LIFT_SIGNED, ROBOT_KEY): the same lift under the shared key
LEGACY_ROBOT_LIFT = bytes.fromhex("01210700010000000c0002006142ad77e552a206")
# An operator (writer 0x0102) sets urgency 9 and destination 3 on tag 5, counter 0x0A0B0C0D.
OPERATOR_SIGNED = bytes([0x01, 0x52, 0x02, 0x01, 0x0D, 0x0C, 0x0B, 0x0A, 0x05, 0x09, 0x00, 0x03])
# OPERATOR_SIGNED + _mac(OPERATOR_SIGNED, OPERATOR_KEY), printed once and pinned:
OPERATOR_WRITE = bytes.fromhex("015202010d0c0b0a0509000343cf8c13231ac429")


@pytest.mark.parametrize(("ikm", "salt", "info", "length", "okm"), RFC_5869_CASES)
def test_independent_hkdf_matches_rfc_5869(ikm, salt, info, length, okm):
    assert _hkdf_rfc5869(ikm, salt, info, length).hex() == okm


def test_pinned_vectors_are_what_the_independent_code_computes():
    for role, key in ROLE_KEYS.items():
        assert _hkdf_rfc5869(KEY, SALT, INFO[role], 32) == key
    assert _robot_key(7) == ROBOT7_KEY
    assert ROBOT_LIFT_SIGNED + _mac(ROBOT_LIFT_SIGNED, ROBOT7_KEY) == ROBOT_LIFT
    assert ROBOT_LIFT_SIGNED + _mac(ROBOT_LIFT_SIGNED, ROBOT_KEY) == LEGACY_ROBOT_LIFT
    assert OPERATOR_SIGNED + _mac(OPERATOR_SIGNED, OPERATOR_KEY) == OPERATOR_WRITE


@pytest.mark.parametrize("role", list(Role))
def test_derive_role_key_golden(role):
    assert derive_role_key(KEY, role) == ROLE_KEYS[role]
    assert derive_role_key(memoryview(KEY), int(role)) == ROLE_KEYS[role]


@pytest.mark.parametrize("writer", [0, 7, 0x0102, 0xFFFF])
def test_derive_robot_key_golden(writer):
    assert derive_robot_key(KEY, writer) == _robot_key(writer)
    assert derive_robot_key(memoryview(KEY), writer) == _robot_key(writer)
    assert derive_robot_key(KEY, 7) == ROBOT7_KEY


def test_golden_robot_write():
    write = Write(
        writer=7, role=Role.ROBOT, counter=1, target=12, change=Change(status=TagStatus.PICKED_UP)
    )
    message = sign(write, ROBOT7_KEY)
    assert message == ROBOT_LIFT
    assert len(message) == 20 == WRITE_LENGTH
    assert verify(message, KEY) == write
    assert verify(message, KEY, shared_robot_key=True) == write


def test_the_shared_robot_key_verifies_only_where_the_tag_accepts_it():
    write = Write(
        writer=7, role=Role.ROBOT, counter=1, target=12, change=Change(status=TagStatus.PICKED_UP)
    )
    assert sign(write, ROBOT_KEY) == LEGACY_ROBOT_LIFT
    with pytest.raises(ForgedWrite):
        verify(LEGACY_ROBOT_LIFT, KEY)
    assert verify(LEGACY_ROBOT_LIFT, KEY, shared_robot_key=True) == write


def test_golden_operator_write():
    write = Write(
        writer=0x0102,
        role=Role.OPERATOR,
        counter=0x0A0B0C0D,
        target=5,
        change=Change(urgency=9, destination=3),
    )
    assert sign(write, OPERATOR_KEY) == OPERATOR_WRITE
    assert verify(OPERATOR_WRITE, KEY) == write


@given(
    writer=st.integers(0, 0xFFFF),
    role=st.sampled_from(Role),
    counter=st.integers(0, 0xFFFF_FFFF),
    target=st.integers(0, 255),
    change=changes,
)
def test_sign_verify_round_trip(writer, role, counter, target, change):
    write = Write(writer=writer, role=role, counter=counter, target=target, change=change)
    key = derive_robot_key(KEY, writer) if role is Role.ROBOT else OPERATOR_KEY
    message = sign(write, key)
    assert len(message) <= 20
    assert verify(message, KEY) == write


def test_wrong_key_is_forged():
    write = Write(writer=1, role=Role.OPERATOR, counter=0, target=1, change=Change(urgency=1))
    with pytest.raises(ForgedWrite):
        verify(sign(write, OPERATOR_KEY), b"another-site-key")
    for wrong in (ROBOT_KEY, derive_role_key(b"another-site-key", Role.OPERATOR), KEY * 2):
        with pytest.raises(ForgedWrite, match="key of the role and writer id it names"):
            verify(sign(write, wrong), KEY)  # KEY * 2: the site key is no role key either


def test_a_site_key_signature_no_longer_verifies():
    """Writes MACed under the site key itself (the scheme before role keys) are refused."""
    old_style = ROBOT_LIFT_SIGNED + hmac.new(KEY, ROBOT_LIFT_SIGNED, hashlib.sha256).digest()[:8]
    with pytest.raises(ForgedWrite):
        verify(old_style, KEY)


@pytest.mark.parametrize("flags", [0x20, 0x23])
def test_role_bits_naming_no_role_are_forged_under_every_key(flags):
    """Role bits 0 and 3 select no role key, so no MAC makes such a write verify."""
    signed = bytes([0x01, flags, 7, 0, 1, 0, 0, 0, 12, 0, 2, 0])
    for key in (
        KEY,
        ROBOT_KEY,
        ROBOT7_KEY,
        OPERATOR_KEY,
        _hkdf_rfc5869(KEY, SALT, b"swarmtag write key v1 ", 32),
    ):
        with pytest.raises(ForgedWrite):
            verify(signed + _mac(signed, key), KEY)


@pytest.mark.parametrize("position", range(20))
def test_any_flipped_byte_is_forged(position):
    message = bytearray(ROBOT_LIFT)
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
        (bytes([0x01, 0xA1, 7, 0, 1, 0, 0, 0, 12, 0, 2, 0]), "reserved bits"),
        (bytes([0x01, 0x29, 7, 0, 1, 0, 0, 0, 12, 0, 2, 0]), "reserved bits"),
        (bytes([0x01, 0x21, 7, 0, 1, 0, 0, 0, 12, 5, 2, 0]), "urgency byte is 5"),
        (bytes([0x01, 0x21, 7, 0, 1, 0, 0, 0, 12, 0, 2, 4]), "destination byte is 4"),
        (bytes([0x01, 0x12, 7, 0, 1, 0, 0, 0, 12, 10, 0, 0]), "urgency 10"),  # an operator's
        (bytes([0x01, 0x21, 7, 0, 1, 0, 0, 0, 12, 0, 3, 0]), "status byte 0x03"),
        (bytes([0x01, 0x01, 7, 0, 1, 0, 0, 0, 12, 0, 0, 0]), "at least one field"),
        (bytes([0x01, 0x02, 7, 0, 1, 0, 0, 0, 12, 0, 9, 0]), "status byte is 9"),
    ],
)
def test_authentic_but_malformed_writes(signed, words):
    """MACed under the key of the role and writer their bytes name, yet not a valid write."""
    with pytest.raises(MalformedWrite, match=words):
        verify(signed + _mac(signed, _key_of(signed)), KEY)


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


@pytest.mark.parametrize(
    "key", [b"", b"short", b"x" * 16, b"x" * 33, "a text key of 32 characters!!!!"]
)
def test_keys_that_are_no_role_keys_refused(key):
    write = Write(writer=1, role=Role.OPERATOR, counter=0, target=0, change=Change(urgency=1))
    with pytest.raises(FieldRangeError, match="key: "):
        sign(write, key)


@pytest.mark.parametrize("key", [b"", b"x" * 15, "a text key of 16+", None])
def test_verify_refuses_short_or_non_bytes_site_keys(key):
    with pytest.raises(FieldRangeError, match="site_key"):
        verify(ROBOT_LIFT, key)


def test_signer_counts_up_from_zero_and_keeps_its_counter():
    signer = WriteSigner(writer=4, role=Role.ROBOT, key=_robot_key(4))
    first = verify(signer.sign(3, Change(status=TagStatus.PICKED_UP)), KEY)
    second = verify(signer.sign(3, Change(status=TagStatus.IDLE)), KEY)
    assert (first.counter, second.counter, signer.counter) == (0, 1, 1)
    resumed = WriteSigner(writer=4, role=Role.ROBOT, key=_robot_key(4), counter=signer.counter)
    assert verify(resumed.sign(3, Change(status=TagStatus.IDLE)), KEY).counter == 2
