"""The persisted tag record and the file store."""

from __future__ import annotations

import zlib

import pytest
from hypothesis import given
from hypothesis import strategies as st

from swarmtag.errors import StateRecordError
from swarmtag.tag import FileStore, TagModel, TagRecord, TagState, TagStatus
from tests.strategies import tag_states

STATE = TagState(urgency=7, status=TagStatus.AWAITING_PICKUP, destination=3, marker=12)


def test_golden_record_bytes():
    record = TagRecord(state=STATE, counters={0x0102: 5, 1: 0xFFFFFFFF})
    body = bytes(
        [
            0x02, 0x07, 0x01, 0x03, 0x0C,  # version 2, state
            0x00, 0x00, 0x00,  # flags (shared robot key off, no lifter), lifter 0
            0x02, 0x00,  # two writers
            0x01, 0x00, 0xFF, 0xFF, 0xFF, 0xFF,  # writer 1, counter 2^32-1
            0x02, 0x01, 0x05, 0x00, 0x00, 0x00,  # writer 0x0102, counter 5
        ]
    )  # fmt: skip
    assert record.to_bytes() == body + zlib.crc32(body).to_bytes(4, "little")


def test_golden_record_bytes_with_lifter_and_shared_robot_key():
    lifted = TagState(urgency=7, status=TagStatus.PICKED_UP, destination=3, marker=12)
    record = TagRecord(state=lifted, counters={9: 4}, lifter=9, shared_robot_key=True)
    body = bytes(
        [
            0x02, 0x07, 0x02, 0x03, 0x0C,  # version 2, state (PICKED_UP)
            0x03, 0x09, 0x00,  # flags: shared robot key | lifter; lifter 9
            0x01, 0x00,  # one writer
            0x09, 0x00, 0x04, 0x00, 0x00, 0x00,  # writer 9, counter 4
        ]
    )  # fmt: skip
    assert record.to_bytes() == _with_crc(body)
    assert TagRecord.from_bytes(_with_crc(body)) == record


def test_a_version_1_record_boots_accepting_the_shared_robot_key():
    """Tag state files from before per-robot keys keep working: as they did (issue 35)."""
    body = bytes(
        [
            0x01, 0x07, 0x02, 0x03, 0x0C, 0x01, 0x00,  # version 1, PICKED_UP, one writer
            0x09, 0x00, 0x04, 0x00, 0x00, 0x00,  # writer 9, counter 4
        ]
    )  # fmt: skip
    record = TagRecord.from_bytes(_with_crc(body))
    lifted = TagState(urgency=7, status=TagStatus.PICKED_UP, destination=3, marker=12)
    assert record == TagRecord(state=lifted, counters={9: 4}, lifter=None, shared_robot_key=True)
    assert record.to_bytes()[0] == 0x02  # saved again as version 2, the setting kept


@given(
    tag_states,
    st.dictionaries(st.integers(0, 0xFFFF), st.integers(0, 0xFFFFFFFF), max_size=20),
    st.integers(0, 0xFFFF) | st.none(),
    st.booleans(),
)
def test_record_round_trip(state, counters, lifter, shared):
    if state.status is not TagStatus.PICKED_UP:
        lifter = None
    record = TagRecord(state=state, counters=counters, lifter=lifter, shared_robot_key=shared)
    assert TagRecord.from_bytes(record.to_bytes()) == record


@pytest.mark.parametrize("cut", [0, 3, 10, 12])
def test_truncated_records_refused(cut):
    data = TagRecord(state=STATE, counters={1: 2}).to_bytes()
    with pytest.raises(StateRecordError):
        TagRecord.from_bytes(data[:cut])


def test_corrupt_record_refused():
    data = bytearray(TagRecord(state=STATE, counters={1: 2}).to_bytes())
    data[3] ^= 0xFF
    with pytest.raises(StateRecordError, match="checksum"):
        TagRecord.from_bytes(bytes(data))


def _with_crc(body: bytes) -> bytes:
    return body + zlib.crc32(body).to_bytes(4, "little")


@pytest.mark.parametrize(
    ("body", "words"),
    [
        (bytes([0x03, 7, 1, 3, 12, 0, 0]), "version 3"),
        (bytes([0x02, 7, 1, 3, 12, 0, 0]), "too short"),
        (bytes([0x02, 7, 1, 3, 12, 4, 0, 0, 0, 0]), "flags 0x04"),
        (bytes([0x02, 7, 2, 3, 12, 0, 9, 0, 0, 0]), "flags 0x00 and lifter"),
        (bytes([0x02, 7, 1, 3, 12, 2, 9, 0, 0, 0]), "lifter only while PICKED_UP"),
        (bytes([0x01, 7, 1, 3, 12, 2, 0, 1, 0, 1, 0, 0, 0]), "2 writers"),
        (bytes([0x02, 7, 1, 3, 12, 0, 0, 0, 2, 0, 1, 0, 1, 0, 0, 0]), "2 writers"),
        (bytes([0x01, 10, 1, 3, 12, 0, 0]), "invalid state"),
        (bytes([0x01, 7, 1, 3, 12, 2, 0, 1, 0, 1, 0, 0, 0, 1, 0, 2, 0, 0, 0]), "twice"),
    ],
)
def test_inconsistent_records_refused(body, words):
    with pytest.raises(StateRecordError, match=words):
        TagRecord.from_bytes(_with_crc(body))


def test_file_store_power_cycle(tmp_path):
    path = tmp_path / "tags" / "tag-12.bin"
    store = FileStore(path)
    assert store.load() is None
    key = bytes(16)
    TagModel.provision(STATE, site_key=key, store=store)
    restored = TagModel.boot(site_key=key, store=FileStore(path))
    assert restored.state == STATE
    assert sorted(p.name for p in path.parent.iterdir()) == ["tag-12.bin"]  # no temp files left


def test_file_store_failed_write_keeps_old_record(tmp_path, monkeypatch):
    path = tmp_path / "tag.bin"
    store = FileStore(path)
    store.save(b"old record")

    def refuse(self, target):
        raise OSError("disk full")

    monkeypatch.setattr("pathlib.Path.replace", refuse)
    with pytest.raises(OSError, match="disk full"):
        store.save(b"new record")
    assert path.read_bytes() == b"old record"
    assert [p.name for p in tmp_path.iterdir()] == ["tag.bin"]
