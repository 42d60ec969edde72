"""Bad arguments to ``swarmtag.tag`` meet a ``SwarmtagError`` subclass, never a raw error.

One regression test per case a hostile tester found, then a Hypothesis sweep
that calls every public callable with arbitrary Python values.
"""

from __future__ import annotations

import re
import signal
import subprocess
import sys
import textwrap
import zlib

import pytest

from swarmtag.errors import (
    FieldRangeError,
    MalformedWrite,
    PayloadError,
    StateRecordError,
    SwarmtagError,
    WriteRejected,
    WriterTableFull,
)
from swarmtag.tag import (
    ATT_ERRORS,
    MAX_WRITERS,
    Change,
    FileStore,
    MemoryStore,
    Role,
    ScanFilter,
    TagModel,
    TagRecord,
    TagState,
    TagStatus,
    WriteSigner,
    apply_change,
    decode,
    decode_manufacturer_data,
    derive_robot_key,
    derive_role_key,
    encode,
    encode_manufacturer_data,
)

KEY = bytes(range(16))  # the site key
ROBOT_KEY = derive_robot_key(KEY, 7)  # robot 7's
OPERATOR_KEY = derive_role_key(KEY, Role.OPERATOR)
STATE = TagState(urgency=7, status=TagStatus.AWAITING_PICKUP, destination=3, marker=12)


def _tag(store: MemoryStore | None = None) -> TagModel:
    return TagModel.provision(STATE, site_key=KEY, store=store or MemoryStore())


# --- TagModel.apply: messages that are not bytes ------------------------------------------


@pytest.mark.parametrize(
    "message",
    ["01210700010000000c000200", None, 1.5, float("nan"), 20, [300] * 20, list(range(20))],
    ids=["str", "None", "float", "nan", "int", "list-over-255", "list-of-bytes"],
)
def test_apply_refuses_non_bytes_with_malformed_write(message):
    store = MemoryStore()
    tag = _tag(store)
    before = store.load()
    with pytest.raises(MalformedWrite, match=type(message).__name__) as caught:
        tag.apply(message)
    assert isinstance(caught.value, WriteRejected)
    assert caught.value.att_error == 0x0D
    assert (tag.state, dict(tag.counters), store.load()) == (STATE, {}, before)


@pytest.mark.parametrize("wrap", [bytes, bytearray, memoryview])
def test_apply_accepts_every_bytes_like_form(wrap):
    robot = WriteSigner(writer=7, role=Role.ROBOT, key=ROBOT_KEY)
    tag = _tag()
    assert tag.apply(wrap(robot.sign(12, Change(status=TagStatus.PICKED_UP)))).status is (
        TagStatus.PICKED_UP
    )


# --- the writer table: a documented capacity, WriterTableFull beyond it ----------------------


def _full_tag() -> tuple[TagModel, MemoryStore]:
    """A tag that already tracks MAX_WRITERS writers (ids 0, 128, 256, ... up to 0xFFFF)."""
    writers = [*range(0, 128 * (MAX_WRITERS - 1), 128), 0xFFFF]
    store = MemoryStore()
    store.save(TagRecord(state=STATE, counters=dict.fromkeys(writers, 5)).to_bytes())
    return TagModel.boot(site_key=KEY, store=store), store


def test_writer_table_capacity_fits_the_record_and_a_flash_page():
    assert 0 < MAX_WRITERS <= 0xFFFF  # the record's 16-bit count can say it
    assert len(_full_tag()[1].load() or b"") <= 4096  # one nRF52833 flash page


def test_new_writer_beyond_capacity_is_refused_and_changes_nothing():
    tag, store = _full_tag()
    before = store.load()
    newcomer = WriteSigner(writer=1, role=Role.OPERATOR, key=OPERATOR_KEY)
    with pytest.raises(WriterTableFull, match=f"{MAX_WRITERS} writers") as caught:
        tag.apply(newcomer.sign(12, Change(urgency=9)))
    assert caught.value.att_error == 0x85
    assert ATT_ERRORS[WriterTableFull] == 0x85
    assert tag.state == STATE
    assert len(tag.counters) == MAX_WRITERS
    assert 1 not in tag.counters
    assert store.load() == before


def test_known_writers_keep_working_when_the_table_is_full():
    tag, store = _full_tag()
    known = WriteSigner(writer=0xFFFF, role=Role.OPERATOR, key=OPERATOR_KEY, counter=5)
    assert tag.apply(known.sign(12, Change(urgency=1))).urgency == 1
    assert tag.counters[0xFFFF] == 6
    assert len(tag.counters) == MAX_WRITERS
    assert TagModel.boot(site_key=KEY, store=store).counters == tag.counters


def test_full_writer_table_round_trips_through_the_record():
    record = TagRecord(state=STATE, counters={w: w * 3 for w in range(MAX_WRITERS)})
    assert TagRecord.from_bytes(record.to_bytes()) == record


def test_records_beyond_capacity_are_refused():
    with pytest.raises(FieldRangeError, match=str(MAX_WRITERS)):
        TagRecord(state=STATE, counters=dict.fromkeys(range(MAX_WRITERS + 1), 0))
    count = MAX_WRITERS + 1
    body = bytes([0x01, 7, 1, 3, 12]) + count.to_bytes(2, "little")
    body += b"".join(w.to_bytes(2, "little") + bytes(4) for w in range(count))
    with pytest.raises(StateRecordError, match=f"{count} writers"):
        TagRecord.from_bytes(body + zlib.crc32(body).to_bytes(4, "little"))


# --- WriteSigner: every argument checked at construction -------------------------------------


@pytest.mark.parametrize(
    ("fields", "words"),
    [
        ({"role": 3}, r"role: 3 .*Role\.ROBOT \(1\) or Role\.OPERATOR \(2\)"),
        ({"role": 0}, "role: 0"),
        ({"role": "robot"}, "role: 'robot'"),
        ({"role": None}, "role: None"),
        ({"role": 1.0}, "role: 1.0"),
        ({"role": True}, "role: True"),
        ({"key": "a text key of 16+"}, "key: .*got str"),
        ({"key": None}, "key: .*got NoneType"),
        ({"key": b"short"}, "key: a writer's key is 32 bytes, got 5"),
        ({"key": KEY}, r"key: a writer's key is 32 bytes, got 16; get one with derive_robot_key"),
        ({"key": 16}, "key: .*got int"),
        ({"writer": -1}, "writer: -1"),
        ({"writer": 0x10000}, "writer: 65536"),
        ({"writer": "7"}, "writer: '7'"),
        ({"writer": 2**80}, "writer: an integer of 81 bits"),
        ({"counter": -2}, "counter: -2"),
        ({"counter": 2**32}, "counter"),
        ({"counter": 1.5}, "counter: 1.5"),
        ({"counter": None}, "counter: None"),
    ],
)
def test_write_signer_arguments_refused(fields, words):
    with pytest.raises(FieldRangeError, match=words):
        WriteSigner(**{"writer": 7, "role": Role.ROBOT, "key": ROBOT_KEY, **fields})


def test_write_signer_accepts_role_numbers_and_key_views():
    signer = WriteSigner(writer=7, role=2, key=memoryview(OPERATOR_KEY))
    assert signer.role is Role.OPERATOR
    assert signer.key == OPERATOR_KEY


def test_exhausted_or_corrupted_counter_refused_without_advancing():
    signer = WriteSigner(writer=7, role=Role.OPERATOR, key=OPERATOR_KEY, counter=0xFFFF_FFFF)
    with pytest.raises(FieldRangeError, match="last counter"):
        signer.sign(12, Change(urgency=1))
    assert signer.counter == 0xFFFF_FFFF
    signer.counter = "9"  # a corrupted persisted counter
    with pytest.raises(FieldRangeError, match="counter: '9'"):
        signer.sign(12, Change(urgency=1))
    signer.counter = 4
    with pytest.raises(FieldRangeError, match="target"):
        signer.sign(256, Change(urgency=1))
    assert signer.counter == 4


# --- FileStore: folder paths and leftovers of a killed save ----------------------------------


def test_file_store_refuses_a_folder_path(tmp_path):
    with pytest.raises(StateRecordError, match=re.escape(str(tmp_path))):
        FileStore(tmp_path)


def test_file_store_refuses_paths_it_cannot_use(tmp_path):
    blocker = tmp_path / "a-file"
    blocker.write_bytes(b"")
    with pytest.raises(StateRecordError, match="is a file, not a folder"):
        FileStore(blocker / "tag.bin")
    for bad in (None, 12, b"tag.bin", "", "tag\0.bin"):
        with pytest.raises(StateRecordError, match="FileStore path"):
            FileStore(bad)


def test_file_store_refuses_a_folder_that_appears_later(tmp_path):
    path = tmp_path / "tag.bin"
    store = FileStore(path)
    path.mkdir()
    with pytest.raises(StateRecordError, match="folder"):
        store.load()
    with pytest.raises(StateRecordError, match="folder"):
        store.save(b"record")
    with pytest.raises(StateRecordError, match="record: expected bytes"):
        FileStore(tmp_path / "other.bin").save("record")


@pytest.mark.skipif(sys.platform == "win32", reason="needs SIGKILL")
def test_file_store_removes_temporaries_left_by_a_killed_save(tmp_path):
    path = tmp_path / "tag-12.bin"
    script = textwrap.dedent(
        """
        import os, signal, sys
        from swarmtag.tag import FileStore
        store = FileStore(sys.argv[1])
        store.save(b"old record")
        os.fsync = lambda fd: os.kill(os.getpid(), signal.SIGKILL)  # die in mid-save
        store.save(b"new record")
        """
    )
    done = subprocess.run([sys.executable, "-c", script, str(path)], check=False, timeout=60)
    assert done.returncode == -signal.SIGKILL
    stale, record = sorted(p.name for p in tmp_path.iterdir())
    assert re.fullmatch(r"\.tag-12\.bin\.[0-9a-f]{12}\.tmp", stale)
    store = FileStore(path)  # the next boot
    assert [p.name for p in tmp_path.iterdir()] == [record]
    assert store.load() == b"old record"


def test_file_store_cleanup_touches_only_its_own_temporaries(tmp_path):
    own = [".tag.bin.0123456789ab.tmp", ".tag.bin.fedcba987654.tmp"]
    others = [
        ".tag.bin.0123456789AB.tmp",  # not what atomic_path writes (lowercase hex)
        ".tag.bin.0123.tmp",
        ".tag.bin.0123456789ab.tmp.bak",
        ".tag2.bin.0123456789ab.tmp",  # another record's temporary
        "tag.bin.0123456789ab.tmp",
        "notes.txt",
    ]
    for name in own + others:
        (tmp_path / name).write_bytes(b"x")
    (tmp_path / ".tag.bin.aaaaaaaaaaaa.tmp").mkdir()  # a folder, not a temporary file
    target = tmp_path / "notes.txt"
    (tmp_path / ".tag.bin.bbbbbbbbbbbb.tmp").symlink_to(target)
    (tmp_path / "sub").mkdir()
    (tmp_path / "sub" / own[0]).write_bytes(b"x")
    FileStore(tmp_path / "tag.bin")
    remaining = {p.name for p in tmp_path.iterdir()}
    assert remaining == {*others, ".tag.bin.aaaaaaaaaaaa.tmp", ".tag.bin.bbbbbbbbbbbb.tmp", "sub"}
    assert target.read_bytes() == b"x"
    assert (tmp_path / "sub" / own[0]).exists()


# --- the rest of the public names ------------------------------------------------------------


def _state(**fields):
    return TagState(**{"urgency": 1, "status": 1, "destination": 0, "marker": 0, **fields})


@pytest.mark.parametrize(
    ("call", "error", "words"),
    [
        (lambda: decode("ffff0701030c"), PayloadError, "got str"),
        (lambda: decode(None), PayloadError, "got NoneType"),
        (lambda: decode(6), PayloadError, "got int"),  # bytes(6) would be six zero bytes
        (lambda: decode([0xFF] * 6), PayloadError, "got list"),
        (lambda: decode_manufacturer_data(b"\xff\xff"), PayloadError, "mapping"),
        (lambda: decode_manufacturer_data({0xFFFF: "abcd"}), PayloadError, "got str"),
        (lambda: decode_manufacturer_data({"x": b"", 1: b""}), PayloadError, "'x', 0x0001"),
        (lambda: encode(42), FieldRangeError, "state: expected a TagState, got int"),
        (lambda: encode_manufacturer_data(None), FieldRangeError, "state"),
        (lambda: _state(urgency="3"), FieldRangeError, "urgency: '3'"),
        (lambda: _state(urgency=10), FieldRangeError, "urgency: 10 is not an integer in 0-9"),
        (lambda: _state(urgency=10**5000), FieldRangeError, "urgency: an integer of"),
        (lambda: _state(marker=float("inf")), FieldRangeError, "marker: inf"),
        (lambda: _state(status=1.0), FieldRangeError, "status: 1.0"),
        (lambda: _state(status=[1]), FieldRangeError, "status: a list"),
        (lambda: _state(status=10**5000), FieldRangeError, "status: an integer of"),
        (lambda: TagStatus(7), FieldRangeError, "status: 7 is not a tag status"),
        (lambda: TagStatus.parse(None), FieldRangeError, "status: None"),
        (lambda: TagStatus.parse("²"), FieldRangeError, "status"),
        (lambda: TagStatus.parse("9" * 5000), FieldRangeError, "status"),
        (lambda: Role(3), FieldRangeError, "role: 3"),
        (lambda: Change(urgency="9"), FieldRangeError, "urgency: '9'"),
        (lambda: Change(status="lifted"), FieldRangeError, "status: 'lifted'"),
        (lambda: apply_change(None, Change(urgency=1), Role.OPERATOR), FieldRangeError, "state"),
        (lambda: apply_change(STATE, {"urgency": 1}, Role.OPERATOR), FieldRangeError, "change"),
        (lambda: apply_change(STATE, Change(urgency=1), 3), FieldRangeError, "role: 3"),
        (lambda: TagRecord(state=STATE, counters=None), FieldRangeError, "counters"),
        (lambda: TagRecord(state=STATE, counters={-1: 0}), FieldRangeError, "writer id: -1"),
        (lambda: TagRecord(state=STATE, counters={1: 2**32}), FieldRangeError, "counter"),
        (lambda: TagRecord.from_bytes("record"), StateRecordError, "got str"),
        (lambda: MemoryStore().save(None), StateRecordError, "record: expected bytes"),
        (lambda: TagModel.boot(site_key=KEY, store=None), FieldRangeError, "store"),
        (lambda: TagModel(STATE, site_key=KEY, store=MemoryStore()), FieldRangeError, "record"),
        (lambda: ScanFilter(accepted=-1), FieldRangeError, "accepted: -1"),
        (lambda: ScanFilter(errors={"x": 1}), FieldRangeError, "errors: expected a Counter"),
    ],
)
def test_public_names_refuse_bad_arguments_with_typed_errors(call, error, words):
    with pytest.raises(error, match=words):
        call()


def test_provision_checks_everything_before_saving():
    store = MemoryStore()
    with pytest.raises(FieldRangeError, match="site_key"):
        TagModel.provision(STATE, site_key=b"short", store=store)
    assert store.load() is None


def test_scan_filter_counts_non_bytes_input_as_malformed():
    scan = ScanFilter()
    for junk in ("ffff0701030c", None, 3.5, [1, 2], {0xFFFF: "abcd"}):
        assert scan.feed(junk) is None
    assert (scan.accepted, scan.foreign, scan.malformed) == (0, 0, 5)
    assert scan.errors["PayloadError"] == 5


def test_enum_refusals_are_still_value_errors():
    """Code that caught ``ValueError`` from ``TagStatus(n)`` or ``Role(n)`` keeps working."""
    for call in (lambda: TagStatus(3), lambda: Role(0)):
        with pytest.raises(ValueError, match="is not a") as caught:
            call()
        assert isinstance(caught.value, SwarmtagError)
