"""A robot's key cannot produce a write that a tag accepts as an operator's (issue 11).

The attacker here holds everything a compromised robot holds: its own robot
key, its writer id and counter, and every write it has ever seen on the air
(including genuine operator writes). Each trick must end in ``ForgedWrite``
with the tag exactly as it was: state, counters and persisted record.
"""

from __future__ import annotations

import hashlib
import hmac

import pytest
from hypothesis import given
from hypothesis import strategies as st

from swarmtag.errors import ForgedWrite, RoleNotAllowed, WriteRejected
from swarmtag.tag import (
    Change,
    MemoryStore,
    Role,
    TagModel,
    TagState,
    TagStatus,
    Write,
    WriteSigner,
    derive_robot_key,
    derive_role_key,
    sign,
)
from swarmtag.tag.keys import HKDF_SALT, ROLE_KEY_INFO, hkdf_sha256
from tests.strategies import changes

SITE_KEY = bytes.fromhex("8f1e2d3c4b5a69788796a5b4c3d2e1f00f1e2d3c4b5a69788796a5b4c3d2e1f0")
ROBOT_ID, OPERATOR_ID = 3, 0xFFFE
ROBOT_KEY = derive_robot_key(SITE_KEY, ROBOT_ID)  # all the attacker has
OPERATOR_KEY = derive_role_key(SITE_KEY, Role.OPERATOR)  # only for the honest control writes
MARKER = 12
URGENT = Change(urgency=0, destination=7)


def _tag() -> tuple[TagModel, MemoryStore]:
    store = MemoryStore()
    start = TagState(urgency=4, status=TagStatus.AWAITING_PICKUP, destination=1, marker=MARKER)
    return TagModel.provision(start, site_key=SITE_KEY, store=store), store


def _operator_write(counter: int, change: Change = URGENT, writer: int = OPERATOR_ID) -> Write:
    return Write(writer=writer, role=Role.OPERATOR, counter=counter, target=MARKER, change=change)


def _mac(key: bytes, signed: bytes) -> bytes:
    return hmac.new(key, signed, hashlib.sha256).digest()[:8]


def _with_role_bits(message: bytes, bits: int) -> bytes:
    """``message`` with its role bits replaced and its MAC left as it was."""
    return bytes([message[0], (message[1] & ~0x03) | bits]) + message[2:]


def _tricks() -> dict[str, bytes]:
    """Every way we could think of to turn ROBOT_KEY into an accepted operator write."""
    robot = WriteSigner(writer=ROBOT_ID, role=Role.ROBOT, key=ROBOT_KEY, counter=99)
    lift = robot.sign(MARKER, Change(status=TagStatus.PICKED_UP))  # a genuine robot write
    robot_urgency = robot.sign(MARKER, URGENT)  # genuine robot MAC, operator's fields
    seen = sign(_operator_write(5), OPERATOR_KEY)  # a genuine operator write it overheard
    signed = sign(_operator_write(10**6), ROBOT_KEY)[:12]
    return {
        "robot key, operator role bits": sign(_operator_write(10**6), ROBOT_KEY),
        "robot key, operator role bits, robot's own id": sign(
            _operator_write(10**6, writer=ROBOT_ID), ROBOT_KEY
        ),
        "robot key in an operator's WriteSigner": WriteSigner(
            writer=OPERATOR_ID, role=Role.OPERATOR, key=ROBOT_KEY, counter=10**6
        ).sign(MARKER, URGENT),
        "robot write, role bits flipped to operator": _with_role_bits(lift, 2),
        "robot write with operator fields, role bits flipped": _with_role_bits(robot_urgency, 2),
        "robot write, role bits set to 3 (both)": _with_role_bits(lift, 3),
        "robot write, role bits cleared to 0": _with_role_bits(robot_urgency, 0),
        "robot key used as a site key to derive an operator key": sign(
            _operator_write(10**6), derive_role_key(ROBOT_KEY, Role.OPERATOR)
        ),
        "robot key as the HKDF pseudorandom key, operator info": sign(
            _operator_write(10**6),
            hmac.new(ROBOT_KEY, ROLE_KEY_INFO[Role.OPERATOR] + b"\x01", hashlib.sha256).digest(),
        ),
        "robot key re-derived with the operator info": sign(
            _operator_write(10**6),
            hkdf_sha256(ROBOT_KEY, salt=HKDF_SALT, info=ROLE_KEY_INFO[Role.OPERATOR], length=32),
        ),
        "robot key, info-less derivation": sign(
            _operator_write(10**6), hkdf_sha256(ROBOT_KEY, salt=HKDF_SALT, info=b"", length=32)
        ),
        "robot key xor'ed with the two info strings": sign(
            _operator_write(10**6),
            bytes(
                k ^ i for k, i in zip(ROBOT_KEY, b"robot-operator".ljust(32, b"\0"), strict=True)
            ),
        ),
        "operator write overheard, new counter, MAC kept": seen[:4]
        + (10**6).to_bytes(4, "little")
        + seen[8:],
        "operator write overheard, new fields, MAC kept": seen[:9] + bytes([9, 0, 200]) + seen[12:],
        "operator MAC spliced onto robot-signed bytes": signed + seen[12:],
        "MAC over the operator bytes under both keys, xor'ed": signed
        + bytes(a ^ b for a, b in zip(_mac(ROBOT_KEY, signed), seen[12:], strict=True)),
        "all-zero MAC": signed + bytes(8),
        "robot key cut to 16 bytes, as a site key of old": signed + _mac(ROBOT_KEY[:16], signed),
    }


@pytest.mark.parametrize(("trick", "message"), list(_tricks().items()), ids=list(_tricks()))
def test_robot_key_cannot_make_an_operator_write(trick, message):
    tag, store = _tag()
    before = (tag.state, dict(tag.counters), store.load())
    with pytest.raises(ForgedWrite) as caught:
        tag.apply(message)
    assert caught.value.att_error == 0x80, trick
    assert (tag.state, dict(tag.counters), store.load()) == before


def test_robot_role_asking_for_operator_fields_is_refused_by_the_role_rules():
    """With its own role bits the robot's MAC verifies, and the role rules refuse it."""
    tag, store = _tag()
    before = (tag.state, dict(tag.counters), store.load())
    robot = WriteSigner(writer=ROBOT_ID, role=Role.ROBOT, key=ROBOT_KEY)
    with pytest.raises(RoleNotAllowed):
        tag.apply(robot.sign(MARKER, URGENT))
    assert (tag.state, dict(tag.counters), store.load()) == before


def test_honest_writes_still_work_after_every_trick():
    tag, _store = _tag()
    for message in _tricks().values():
        with pytest.raises(WriteRejected):
            tag.apply(message)
    operator = WriteSigner(writer=OPERATOR_ID, role=Role.OPERATOR, key=OPERATOR_KEY)
    assert tag.apply(operator.sign(MARKER, URGENT)).urgency == 0
    robot = WriteSigner(writer=ROBOT_ID, role=Role.ROBOT, key=ROBOT_KEY)
    assert tag.apply(robot.sign(MARKER, Change(status=TagStatus.PICKED_UP))).status is (
        TagStatus.PICKED_UP
    )
    assert dict(tag.counters) == {OPERATOR_ID: 0, ROBOT_ID: 0}


def test_role_keys_differ_from_each_other_and_from_the_site_key():
    assert len({SITE_KEY, ROBOT_KEY, OPERATOR_KEY}) == 3
    assert OPERATOR_KEY not in {derive_role_key(ROBOT_KEY, role) for role in Role}


@given(
    writer=st.integers(0, 0xFFFF),
    counter=st.integers(0, 2**32 - 1),
    change=changes,
    bits=st.sampled_from([0, 2, 3]),
)
def test_any_operator_write_the_robot_key_signs_is_forged(writer, counter, change, bits):
    tag, store = _tag()
    before = (tag.state, dict(tag.counters), store.load())
    write = Write(writer=writer, role=Role.OPERATOR, counter=counter, target=MARKER, change=change)
    with pytest.raises(ForgedWrite):
        tag.apply(_with_role_bits(sign(write, ROBOT_KEY), bits))
    assert (tag.state, dict(tag.counters), store.load()) == before
