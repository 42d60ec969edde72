"""Per-robot keys and the lifter binding (issue 35): what a stolen robot can no longer do.

Every write below is built byte by byte and MACed here with ``hmac``, under
keys derived here by ``_hkdf_rfc5869`` (RFC 5869, checked against the RFC's
vectors in ``test_write.py``), so neither the signer nor the derivation of
swarmtag is trusted to make the attack. The pinned hex values are the golden
vectors of docs/tag-protocol.md §4, which ``test_the_docs_state_these_vectors``
checks.
"""

from __future__ import annotations

import hashlib
import hmac
import os
import stat
import zlib
from pathlib import Path

import pytest
from hypothesis import given
from hypothesis import strategies as st

from swarmtag.errors import (
    ConfigError,
    FieldRangeError,
    ForgedWrite,
    IllegalTransition,
    KeyFileError,
    WriteRejected,
)
from swarmtag.tag import (
    Change,
    FileStore,
    MemoryStore,
    Role,
    TagModel,
    TagState,
    TagStatus,
    WriterKey,
    WriteSigner,
    derive_robot_key,
    derive_role_key,
    read_key_file,
    read_role_key_file,
    read_writer_key_file,
    verify,
    write_key_file,
    write_robot_key_file,
    write_role_key_file,
)
from swarmtag.tag.emulator import SoftwareTag
from swarmtag.tag.keys import HKDF_SALT, ROBOT_KEY_INFO, robot_key_info
from tests.tag.test_write import _hkdf_rfc5869

SITE = b"0123456789abcdef"  # the site key of docs/hardware.md §2, 30313233...
MARKER = 12
ROBOT_INFO = b"swarmtag writer key v1 robot"  # 28 ASCII bytes, then the writer id (uint16 LE)
# _hkdf_rfc5869(SITE, HKDF_SALT, ROBOT_INFO + id, 32), printed once and pinned:
KEY_7 = bytes.fromhex("b896d9da3aec6f70a272c3ee2143f916e43fdb13593237feae8e62738c257db9")
KEY_9 = bytes.fromhex("68bdac169a5618279b071cdd497b11ad68df90aa05f80eecab6450232b4c7883")
OPERATOR_KEY = derive_role_key(SITE, Role.OPERATOR)
# Writes to tag 12, each the 12 signed bytes + HMAC-SHA256(key, them)[:8], printed and pinned:
LIFT_7 = "01210700010000000c0002004edbe4fb3b1c5433"  # robot 7 lifts, counter 1, its key
LIFT_9 = "01210900010000000c00020044699bb099fe010f"  # robot 9 lifts, counter 1, its key
RELEASE_7 = "01210700010000000c0000005ff24faa6b0ee1eb"  # robot 7 releases, counter 1, its key
RELEASE_9 = "01210900020000000c000000480c2c18a87db5c3"  # robot 9 releases, counter 2, its key
FORGED_9 = "01210900010000000c000200f0ff40c2428bd467"  # "robot 9 lifts", MACed with robot 7's key
WAITING = TagState(urgency=5, status=TagStatus.AWAITING_PICKUP, destination=2, marker=MARKER)


def _key(writer: int) -> bytes:
    """Robot ``writer``'s key, derived here without swarmtag."""
    return _hkdf_rfc5869(
        SITE, b"swarmtag hkdf salt v1", ROBOT_INFO + writer.to_bytes(2, "little"), 32
    )


def _write(writer: int, counter: int, status: TagStatus, key: bytes) -> bytes:
    """A robot's status write to tag 12, byte by byte, MACed with ``key``."""
    signed = (
        bytes([0x01, 0x21])  # version 1; role robot | status present
        + writer.to_bytes(2, "little")
        + counter.to_bytes(4, "little")
        + bytes([MARKER, 0, int(status), 0])
    )
    return signed + hmac.new(key, signed, hashlib.sha256).digest()[:8]


def _tag(state: TagState = WAITING, **options: bool) -> tuple[TagModel, MemoryStore]:
    store = MemoryStore()
    return TagModel.provision(state, site_key=SITE, store=store, **options), store


def _refused(tag: TagModel, store: MemoryStore, message: bytes, error: type[WriteRejected]) -> str:
    """Apply ``message``, which must be refused with ``error``, changing nothing; the reason."""
    before = (tag.state, dict(tag.counters), tag.lifter, store.load())
    with pytest.raises(error) as caught:
        tag.apply(message)
    assert (tag.state, dict(tag.counters), tag.lifter, store.load()) == before
    return caught.value.reason


# --- the derivation and its golden vectors -----------------------------------------------------


def test_the_pinned_vectors_are_what_the_independent_code_computes():
    assert ROBOT_KEY_INFO == ROBOT_INFO
    assert HKDF_SALT == b"swarmtag hkdf salt v1"
    assert robot_key_info(7) == ROBOT_INFO + b"\x07\x00"
    assert robot_key_info(0x0102).hex() == ROBOT_INFO.hex() + "0201"
    assert (_key(7), _key(9)) == (KEY_7, KEY_9)
    assert _write(7, 1, TagStatus.PICKED_UP, KEY_7).hex() == LIFT_7
    assert _write(9, 1, TagStatus.PICKED_UP, KEY_9).hex() == LIFT_9
    assert _write(7, 1, TagStatus.IDLE, KEY_7).hex() == RELEASE_7
    assert _write(9, 2, TagStatus.IDLE, KEY_9).hex() == RELEASE_9
    assert _write(9, 1, TagStatus.PICKED_UP, KEY_7).hex() == FORGED_9


@given(writer=st.integers(0, 0xFFFF))
def test_derive_robot_key_is_hkdf_of_the_site_key_and_the_writer_id(writer):
    assert derive_robot_key(SITE, writer) == _key(writer)


def test_swarmtag_signs_the_golden_writes():
    robot = WriteSigner(writer=7, role=Role.ROBOT, key=derive_robot_key(SITE, 7), counter=0)
    assert robot.sign(MARKER, Change(status=TagStatus.PICKED_UP)).hex() == LIFT_7


def test_every_robot_key_differs_and_none_is_a_role_key():
    keys = {derive_robot_key(SITE, writer) for writer in range(300)}
    keys |= {derive_role_key(SITE, role) for role in Role}
    assert len(keys) == 302


def test_the_docs_state_these_vectors():
    text = (Path(__file__).parents[2] / "docs" / "tag-protocol.md").read_text(encoding="utf-8")
    for value in (SITE.hex(), ROBOT_INFO.decode(), (ROBOT_INFO + b"\x07\x00").hex(), KEY_7.hex(),
                  KEY_9.hex(), LIFT_7, LIFT_9, RELEASE_7, RELEASE_9, FORGED_9):  # fmt: skip
        assert value in text, value


# --- a robot's key signs only for its own writer id ------------------------------------------


def test_a_write_maced_with_robot_7s_key_but_carrying_writer_id_9_is_refused():
    tag, store = _tag()
    reason = _refused(tag, store, bytes.fromhex(FORGED_9), ForgedWrite)
    assert "key of the role and writer id it names" in reason
    assert ForgedWrite("").att_error == 0x80
    assert tag.apply(bytes.fromhex(LIFT_7)).status is TagStatus.PICKED_UP  # its own id works


@given(writer=st.integers(0, 0xFFFF).filter(lambda w: w != 7), counter=st.integers(0, 2**32 - 1))
def test_a_stolen_robot_key_can_neither_spend_other_ids_nor_fill_the_writer_table(writer, counter):
    """Any writer id but its own, at any counter (2^32-1 would lock that robot out): forged."""
    tag, store = _tag()
    for status in TagStatus:
        _refused(tag, store, _write(writer, counter, status, KEY_7), ForgedWrite)
    assert dict(tag.counters) == {}


def test_robot_9_is_not_locked_out_by_robot_7():
    tag, _store = _tag()
    with pytest.raises(ForgedWrite):
        tag.apply(_write(9, 2**32 - 1, TagStatus.PICKED_UP, KEY_7))
    assert tag.apply(bytes.fromhex(LIFT_9)).status is TagStatus.PICKED_UP
    assert dict(tag.counters) == {9: 1}


def test_the_shared_robot_key_is_refused_unless_the_tag_is_set_to_accept_it():
    shared = derive_role_key(SITE, Role.ROBOT)
    tag, store = _tag()
    assert tag.shared_robot_key is False
    _refused(tag, store, _write(7, 1, TagStatus.PICKED_UP, shared), ForgedWrite)
    legacy, _legacy_store = _tag(shared_robot_key=True)
    assert legacy.apply(_write(7, 1, TagStatus.PICKED_UP, shared)).status is TagStatus.PICKED_UP
    assert legacy.apply(_write(7, 2, TagStatus.IDLE, KEY_7)).status is TagStatus.IDLE  # both keys


def test_the_legacy_setting_survives_a_power_cycle_and_can_be_turned_off(tmp_path):
    shared = derive_role_key(SITE, Role.ROBOT)
    store = FileStore(tmp_path / "tag.state")
    TagModel.provision(WAITING, site_key=SITE, store=store, shared_robot_key=True)
    tag = TagModel.boot(site_key=SITE, store=store)
    assert tag.shared_robot_key is True
    tag.apply(_write(7, 1, TagStatus.PICKED_UP, shared))
    tag.set_shared_robot_key(False)  # every robot now has its own key
    rebooted = TagModel.boot(site_key=SITE, store=store)
    assert (rebooted.shared_robot_key, dict(rebooted.counters), rebooted.lifter) == (
        False,
        {7: 1},
        7,
    )
    with pytest.raises(ForgedWrite):
        rebooted.apply(_write(7, 2, TagStatus.IDLE, shared))
    assert rebooted.apply(_write(7, 2, TagStatus.IDLE, KEY_7)).status is TagStatus.IDLE


def test_a_version_1_state_file_keeps_working_with_the_shared_key(tmp_path):
    """A tag state file written before per-robot keys boots accepting what it accepted."""

    body = bytes([0x01, 5, 1, 2, MARKER, 0, 0])  # version 1, AWAITING_PICKUP, no writers
    path = tmp_path / "old.state"
    path.write_bytes(body + zlib.crc32(body).to_bytes(4, "little"))
    tag = SoftwareTag.boot(site_key=SITE, store=FileStore(path))
    assert tag.shared_robot_key is True
    shared = derive_role_key(SITE, Role.ROBOT)
    assert tag.write(_write(7, 1, TagStatus.PICKED_UP, shared)).accepted
    assert path.read_bytes()[0] == 0x02  # rewritten as version 2, the setting kept
    assert TagModel.boot(site_key=SITE, store=FileStore(path)).shared_robot_key is True


def test_verify_picks_the_key_from_the_role_bits_and_writer_id():
    assert verify(bytes.fromhex(LIFT_9), SITE).writer == 9
    with pytest.raises(ForgedWrite):
        verify(bytes.fromhex(FORGED_9), SITE)
    with pytest.raises(ForgedWrite):
        verify(bytes.fromhex(FORGED_9), SITE, shared_robot_key=True)


# --- lift and release: only the robot that lifted a carrier releases it -----------------------


def test_robot_7_cannot_release_a_carrier_robot_9_lifted():
    tag, store = _tag()
    assert tag.apply(bytes.fromhex(LIFT_9)).status is TagStatus.PICKED_UP
    assert tag.lifter == 9
    reason = _refused(tag, store, bytes.fromhex(RELEASE_7), IllegalTransition)
    assert reason == (
        "robot 7 may not release this carrier: robot 9 lifted it (only that robot, or an "
        "operator, may)"
    )
    assert IllegalTransition("").att_error == 0x84
    assert tag.apply(bytes.fromhex(RELEASE_9)).status is TagStatus.IDLE
    assert (tag.lifter, dict(tag.counters)) == (None, {9: 2})


@pytest.mark.parametrize("status", [TagStatus.IDLE, TagStatus.AWAITING_PICKUP])
def test_an_operator_may_release_a_carrier_any_robot_lifted(status):
    tag, _store = _tag()
    tag.apply(bytes.fromhex(LIFT_9))
    operator = WriteSigner(writer=256, role=Role.OPERATOR, key=OPERATOR_KEY)
    assert tag.apply(operator.sign(MARKER, Change(urgency=9))).status is TagStatus.PICKED_UP
    assert tag.lifter == 9  # a write that keeps PICKED_UP keeps the lifter
    assert tag.apply(operator.sign(MARKER, Change(status=status))).status is status
    assert tag.lifter is None
    if status is TagStatus.AWAITING_PICKUP:  # ready again: any robot may lift it now
        assert tag.apply(_write(7, 5, TagStatus.PICKED_UP, KEY_7)).status is TagStatus.PICKED_UP
        assert tag.lifter == 7


def test_a_carrier_an_operator_marked_picked_up_may_be_released_by_any_robot():
    tag, _store = _tag()
    operator = WriteSigner(writer=256, role=Role.OPERATOR, key=OPERATOR_KEY)
    tag.apply(operator.sign(MARKER, Change(status=TagStatus.PICKED_UP)))
    assert tag.lifter is None
    assert tag.apply(bytes.fromhex(RELEASE_7)).status is TagStatus.IDLE


def test_the_lifter_survives_a_power_cycle(tmp_path):
    store = FileStore(tmp_path / "tag.state")
    TagModel.provision(WAITING, site_key=SITE, store=store).apply(bytes.fromhex(LIFT_9))
    rebooted = TagModel.boot(site_key=SITE, store=FileStore(tmp_path / "tag.state"))
    assert rebooted.lifter == 9
    with pytest.raises(IllegalTransition, match="robot 9 lifted it"):
        rebooted.apply(bytes.fromhex(RELEASE_7))
    assert rebooted.apply(bytes.fromhex(RELEASE_9)).status is TagStatus.IDLE


def test_the_software_tag_answers_att_0x84_to_another_robots_release():
    tag = SoftwareTag.open(
        marker=MARKER, site_key=SITE, store=MemoryStore(), status="awaiting_pickup"
    )
    assert tag.write(bytes.fromhex(LIFT_9)).accepted
    outcome = tag.write(bytes.fromhex(RELEASE_7))
    assert (outcome.att_error, outcome.refusal, outcome.state.status) == (
        0x84,
        "IllegalTransition",
        TagStatus.PICKED_UP,
    )
    assert outcome.write is not None
    assert outcome.write.writer == 7


# --- robot key files ---------------------------------------------------------------------------


def _private(path: Path, data: bytes) -> Path:
    path.write_bytes(data)
    path.chmod(0o600)
    return path


def test_a_robot_key_file_holds_its_writer_id_and_key(tmp_path):
    path = write_robot_key_file(tmp_path / "robot7.key", 7, KEY_7)
    assert path.read_bytes() == f"swarmtag-robot-writer-key-v1\n7\n{KEY_7.hex()}\n".encode()
    if os.name == "posix":
        assert stat.S_IMODE(path.stat().st_mode) == 0o600
    assert read_writer_key_file(path) == WriterKey(role=Role.ROBOT, key=KEY_7, writer=7)
    with pytest.raises(KeyFileError, match="already exists"):
        write_robot_key_file(path, 7, KEY_7)
    with pytest.raises(FieldRangeError, match="writer"):
        write_robot_key_file(tmp_path / "x.key", 65536, KEY_7)


def test_role_key_files_are_read_as_shared_keys(tmp_path):
    operator = write_role_key_file(tmp_path / "op.key", Role.OPERATOR, OPERATOR_KEY)
    assert read_writer_key_file(operator) == WriterKey(role=Role.OPERATOR, key=OPERATOR_KEY)
    shared = derive_role_key(SITE, Role.ROBOT)
    legacy = write_role_key_file(tmp_path / "shared.key", Role.ROBOT, shared)
    assert read_writer_key_file(legacy) == WriterKey(role=Role.ROBOT, key=shared, writer=None)


def test_a_robot_key_file_is_neither_a_site_key_nor_a_role_key_file(tmp_path):
    path = write_robot_key_file(tmp_path / "robot7.key", 7, KEY_7)
    with pytest.raises(KeyFileError, match="is a robot key file, not a site key file"):
        read_key_file(path)
    with pytest.raises(KeyFileError, match="is robot 7's key file, bound to its writer id"):
        read_role_key_file(path)
    site = write_key_file(tmp_path / "site.key", bytes(32))
    with pytest.raises(KeyFileError, match="is the site key file, not a writer's key file"):
        read_writer_key_file(site)


GOOD = f"swarmtag-robot-writer-key-v1\n7\n{KEY_7.hex()}\n"


@pytest.mark.parametrize(
    "text",
    [
        GOOD.replace("\n7\n", "\n07\n"),
        GOOD.replace("\n7\n", "\n65536\n"),
        GOOD.replace("\n7\n", "\n-7\n"),
        GOOD.replace("\n7\n", "\n\n"),
        GOOD.replace("\n7\n", "\n"),
        GOOD.replace("\n7\n", "\n7 \n"),
        GOOD.replace("\n7\n", "\n\u0667\n"),  # an Arabic-Indic digit seven
        GOOD.replace("v1", "v2"),
        GOOD + "x\n",
        GOOD.rstrip("\n"),
        GOOD[:-3] + "\n",
    ],
)
def test_bad_robot_key_files_are_refused_without_their_content(tmp_path, text):
    path = _private(tmp_path / "robot.key", text.encode())
    with pytest.raises(KeyFileError, match="is not a swarmtag writer's key file") as caught:
        read_writer_key_file(path)
    assert KEY_7.hex()[:16] not in str(caught.value)


@pytest.mark.parametrize(
    ("fields", "words"),
    [
        ({"role": 3}, "role"),
        ({"key": b"short"}, "key"),
        ({"writer": 65536}, "writer"),
        ({"writer": True}, "writer"),
        ({"role": Role.OPERATOR, "writer": 7}, "only a robot key is bound to a writer id"),
    ],
)
def test_writer_key_fields_are_checked(fields, words):
    with pytest.raises(FieldRangeError, match=words):
        WriterKey(**{"role": Role.ROBOT, "key": KEY_7, "writer": 7, **fields})


def test_the_writer_id_to_sign_with():
    own = WriterKey(role=Role.ROBOT, key=KEY_7, writer=7)
    shared = WriterKey(role=Role.OPERATOR, key=OPERATOR_KEY)
    assert (own.writer_id(None, "r.key"), own.writer_id(7, "r.key"), shared.writer_id(3, "o")) == (
        7,
        7,
        3,
    )
    with pytest.raises(ConfigError, match=r"writer 9 does not match the key file r\.key"):
        own.writer_id(9, "r.key")
    with pytest.raises(ConfigError, match="give this writer's id"):
        shared.writer_id(None, "o.key")
    with pytest.raises(ConfigError, match="writer: 65536 is not a writer id"):
        shared.writer_id(65536, "o.key")
