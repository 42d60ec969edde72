"""A writer's counter file: format, reserve-before-send, restarts, crashes, refusals (issue 11)."""

from __future__ import annotations

import multiprocessing
import os
import sys

import pytest

from swarmtag.errors import CounterFileError, FieldRangeError, ReplayedWrite
from swarmtag.tag import (
    Change,
    MemoryStore,
    Role,
    TagModel,
    TagState,
    TagStatus,
    WriteSigner,
    derive_role_key,
)
from swarmtag.tag import counter as counter_module
from swarmtag.tag.counter import (
    COUNTER_FILE_HEADER,
    CounterFile,
    format_counters,
    parse_counters,
)
from swarmtag.tag.write import MAX_COUNTER

SITE = bytes(range(32))


def test_format_is_the_documented_text():
    assert COUNTER_FILE_HEADER == "swarmtag-writer-counters-v1"
    assert format_counters({65535: MAX_COUNTER, 0: 0, 7: 41}) == (
        b"swarmtag-writer-counters-v1\n0 0\n7 41\n65535 4294967295\n"
    )
    assert format_counters({}) == b"swarmtag-writer-counters-v1\n"
    table = {3: 9, 12: 0, 40000: 123456}
    assert parse_counters(format_counters(table)) == table


@pytest.mark.parametrize(
    "data",
    [
        b"",
        b"swarmtag-writer-counters-v2\n",
        b"swarmtag-writer-counters-v1",  # no line feed
        b"swarmtag-writer-counters-v1\n7 41",  # last line unterminated
        b"swarmtag-writer-counters-v1\n7 41\n7 42\n",  # twice
        b"swarmtag-writer-counters-v1\n9 1\n7 41\n",  # unsorted
        b"swarmtag-writer-counters-v1\n65536 1\n",
        b"swarmtag-writer-counters-v1\n7 4294967296\n",
        b"swarmtag-writer-counters-v1\n7 -1\n",
        b"swarmtag-writer-counters-v1\n07 1\n",
        b"swarmtag-writer-counters-v1\n7  1\n",
        b"swarmtag-writer-counters-v1\n7 1 \n",
        b"swarmtag-writer-counters-v1\n7\n",
        b"swarmtag-writer-counters-v1\n\n",
        b"swarmtag-writer-counters-v1\r\n7 1\r\n",
        b"swarmtag-writer-counters-v1\n\xd9\xa7 1\n",  # an Arabic-Indic digit seven
        b"\xff\xfe",
    ],
    ids=repr,
)
def test_anything_else_is_refused(data):
    with pytest.raises(ValueError):  # noqa: PT011 - each case has its own message
        parse_counters(data)


@pytest.mark.parametrize(("table", "words"), [({-1: 0}, "writer"), ({1: 2**32}, "counter")])
def test_format_refuses_values_the_tags_cannot_hold(table, words):
    with pytest.raises(FieldRangeError, match=words):
        format_counters(table)


def test_reserve_counts_up_per_writer_and_saves_first(tmp_path):
    counters = CounterFile(tmp_path / "w.counters")
    assert counters.check() == {}
    assert [counters.reserve(7) for _ in range(3)] == [0, 1, 2]
    assert counters.reserve(12) == 0
    assert (tmp_path / "w.counters").read_bytes() == b"swarmtag-writer-counters-v1\n7 2\n12 0\n"
    assert (counters.last(7), counters.last(12), counters.last(3)) == (2, 0, None)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["w.counters"]


def test_a_restart_continues_where_the_file_left_off(tmp_path):
    path = tmp_path / "w.counters"
    assert CounterFile(path).reserve(7) == 0
    assert CounterFile(path).reserve(7) == 1  # a new process: the same file, the next value


def test_a_restarted_writer_is_never_refused_as_a_replay(tmp_path):
    """The reason the file exists: a writer that restarts keeps writing to the same tag."""
    tag = TagModel.provision(
        TagState(urgency=3, status=TagStatus.IDLE, destination=0, marker=5),
        site_key=SITE,
        store=MemoryStore(),
    )
    key = derive_role_key(SITE, Role.OPERATOR)
    for urgency in range(5):  # five runs of a writer process, each starting from the file
        counter = CounterFile(tmp_path / "w.counters").reserve(2)
        signer = WriteSigner(writer=2, role=Role.OPERATOR, key=key, counter=counter - 1)
        assert tag.apply(signer.sign(5, Change(urgency=urgency))).urgency == urgency
    assert tag.counters[2] == 4
    amnesiac = WriteSigner(writer=2, role=Role.OPERATOR, key=key)  # what no file would give
    with pytest.raises(ReplayedWrite):
        tag.apply(amnesiac.sign(5, Change(urgency=9)))


def test_a_crash_after_saving_only_skips_a_value(tmp_path):
    """Saved, then killed before sending: the next run uses the next value; tags accept gaps."""
    tag = TagModel.provision(
        TagState(urgency=3, status=TagStatus.IDLE, destination=0, marker=5),
        site_key=SITE,
        store=MemoryStore(),
    )
    key = derive_role_key(SITE, Role.OPERATOR)
    counters = CounterFile(tmp_path / "w.counters")
    counters.reserve(2)  # ... and the process dies here, nothing sent
    counter = CounterFile(tmp_path / "w.counters").reserve(2)
    assert counter == 1
    signer = WriteSigner(writer=2, role=Role.OPERATOR, key=key, counter=counter - 1)
    assert tag.apply(signer.sign(5, Change(urgency=8))).urgency == 8


def test_a_failed_save_reserves_nothing_and_says_nothing_was_sent(tmp_path, monkeypatch):
    counters = CounterFile(tmp_path / "w.counters")
    counters.reserve(7)
    before = (tmp_path / "w.counters").read_bytes()

    def full_disk(_path, _data):
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(counter_module, "atomic_write_bytes", full_disk)
    with pytest.raises(CounterFileError, match=r"cannot save .*No space left.*nothing was sent"):
        counters.reserve(7)
    assert (tmp_path / "w.counters").read_bytes() == before


def test_the_last_counter_retires_the_writer_id(tmp_path):
    path = tmp_path / "w.counters"
    path.write_bytes(format_counters({7: MAX_COUNTER - 1}))
    assert CounterFile(path).reserve(7) == MAX_COUNTER
    before = path.read_bytes()
    with pytest.raises(FieldRangeError, match=r"has used its last counter .*retire this writer id"):
        CounterFile(path).reserve(7)
    assert path.read_bytes() == before
    assert CounterFile(path).reserve(8) == 0  # other ids go on


def test_stale_temporaries_of_a_killed_save_are_removed(tmp_path):
    stale = tmp_path / ".w.counters.0123456789ab.tmp"
    stale.write_bytes(b"half")
    other = tmp_path / ".other.0123456789ab.tmp"
    other.write_bytes(b"not ours")
    CounterFile(tmp_path / "w.counters").reserve(1)
    assert not stale.exists()
    assert other.exists()


def _reserve_many(path: str, writer: int, count: int, queue) -> None:
    queue.put([CounterFile(path).reserve(writer) for _ in range(count)])


@pytest.mark.skipif(sys.platform == "win32", reason="flock is POSIX")
def test_two_processes_never_reserve_the_same_value(tmp_path):
    path = str(tmp_path / "w.counters")
    context = multiprocessing.get_context("spawn")  # no fork of a threaded pytest
    queue = context.Queue()
    workers = [context.Process(target=_reserve_many, args=(path, 7, 40, queue)) for _ in range(3)]
    for worker in workers:
        worker.start()
    got = [value for _ in workers for value in queue.get(timeout=60)]
    for worker in workers:
        worker.join(60)
    assert sorted(got) == list(range(120))
    assert CounterFile(path).last(7) == 119


@pytest.mark.parametrize(
    ("make", "words"),
    [
        (lambda p: p.write_bytes(b"swarmtag-site-key-v1\n" + b"ab" * 32 + b"\n"), "not a swarmtag"),
        (lambda p: p.mkdir(), "is a folder"),
        (os.mkfifo, "not a regular file"),
        (lambda p: p.write_bytes(b"x" * (3 << 20)), "too large"),
    ],
    ids=["a key file", "a folder", "a FIFO", "huge"],
)
def test_unusable_files_are_refused_and_kept(tmp_path, make, words):
    path = tmp_path / "w.counters"
    make(path)
    before = path.read_bytes() if path.is_file() else None
    with pytest.raises(CounterFileError, match=words):
        CounterFile(path).check()
    with pytest.raises(CounterFileError, match=words):
        CounterFile(path).reserve(1)
    assert (path.read_bytes() if path.is_file() else None) == before


def test_a_missing_folder_and_bad_paths_are_refused(tmp_path):
    with pytest.raises(CounterFileError, match="does not exist"):
        CounterFile(tmp_path / "missing" / "w.counters").check()
    assert not (tmp_path / "missing").exists()
    for bad in (None, 3, "", "a\0b"):
        with pytest.raises(CounterFileError, match="counter file path"):
            CounterFile(bad)


@pytest.mark.skipif(
    os.name != "posix" or os.geteuid() == 0, reason="root writes whatever the folder's mode"
)
def test_a_folder_this_user_cannot_write_is_refused_before_any_send(tmp_path):
    folder = tmp_path / "ro"
    folder.mkdir()
    folder.chmod(0o500)
    try:
        with pytest.raises(CounterFileError, match="is not writable"):
            CounterFile(folder / "w.counters").check()
    finally:
        folder.chmod(0o700)


@pytest.mark.parametrize("writer", [-1, 65536, 1.0, True, "7"])
def test_writer_ids_are_checked(tmp_path, writer):
    with pytest.raises(FieldRangeError, match="writer"):
        CounterFile(tmp_path / "w.counters").reserve(writer)
    assert list(tmp_path.iterdir()) == []


# --- a full table: 65,536 writers, parsed in linear time, read once per write (issue 35) ---------


def _full_table() -> dict[int, int]:
    return {writer: (writer * 2_654_435_761) % MAX_COUNTER for writer in range(0x10000)}


def test_a_table_of_all_65536_writers_round_trips_and_reserves(tmp_path):
    table = _full_table()
    data = format_counters(table)
    assert parse_counters(data) == table
    path = tmp_path / "w.counters"
    path.write_bytes(data)
    counters = CounterFile(path)
    assert counters.check() == table
    assert [counters.reserve(writer) for writer in (0, 7, 65535, 7)] == [
        table[0] + 1,
        table[7] + 1,
        table[65535] + 1,
        table[7] + 2,
    ]
    expected = {**table, 0: table[0] + 1, 7: table[7] + 2, 65535: table[65535] + 1}
    assert parse_counters(path.read_bytes()) == expected
    assert CounterFile(path).check() == expected  # another process reads the same


def test_the_largest_table_fits_the_file_limit():
    data = format_counters(dict.fromkeys(range(0x10000), MAX_COUNTER))
    assert len(data) < counter_module._MAX_FILE_BYTES
    assert parse_counters(data)[65535] == MAX_COUNTER


@pytest.mark.parametrize(
    ("body", "words"),
    [
        (b"0 1\n1 2\n1 3\n", "line 4: writer ids are not in increasing order"),
        (b"0 1\n2 2\n1 3\n", "line 4: writer ids are not in increasing order"),
        (b"0 1\n65536 2\n", "line 3 is not '<writer id> <counter>' in range"),
        (b"0 1\n1 4294967296\n", "line 3 is not '<writer id> <counter>' in range"),
        (b"0 1\n1 x\n", "line 3 is not '<writer id> <counter>' in range"),
    ],
)
def test_a_bad_line_is_named_in_a_long_file_too(body, words):
    data = format_counters(dict.fromkeys(range(100, 60_100), 5)).replace(b"\n100 5\n", b"\n")
    head = data[: data.index(b"\n") + 1]
    with pytest.raises(ValueError, match=words):
        parse_counters(head + body + data[len(head) :])


def test_crlf_line_ends_are_read_as_before():
    assert parse_counters(b"swarmtag-writer-counters-v1\n7 41\r\n9 1\r\n") == {7: 41, 9: 1}


def _counting_parses(monkeypatch) -> list[int]:
    """Count the reads of counter files (each read is parsed once); treat new files as settled."""
    calls: list[int] = []
    real = counter_module.parse_counters

    def counted(data: bytes) -> dict[int, int]:
        calls.append(len(data))
        return real(data)

    monkeypatch.setattr(counter_module, "parse_counters", counted)
    monkeypatch.setattr(counter_module, "_SETTLED_NS", 0)
    return calls


def test_a_write_reads_the_counter_file_once(tmp_path, monkeypatch):
    """check (before the radio), check again (the writer), reserve: one read of the file."""
    path = tmp_path / "w.counters"
    path.write_bytes(format_counters(_full_table()))
    calls = _counting_parses(monkeypatch)
    counters = CounterFile(path)
    counters.check()
    counters.check()
    assert counters.reserve(7) == _full_table()[7] + 1
    assert len(calls) == 1
    assert counters.reserve(7) == _full_table()[7] + 2  # the file it wrote itself: not read
    assert len(calls) == 1


def test_a_file_another_process_replaced_is_read_again(tmp_path, monkeypatch):
    path = tmp_path / "w.counters"
    path.write_bytes(format_counters({7: 10}))
    calls = _counting_parses(monkeypatch)
    ours = CounterFile(path)
    ours.check()
    assert CounterFile(path).reserve(7) == 11  # another process, between our check and reserve
    assert ours.reserve(7) == 12
    assert len(calls) == 3


def test_a_file_changed_just_before_it_was_read_is_not_trusted_again(tmp_path, monkeypatch):
    """Within 2 s of a change, another file could carry the same identity: read again."""
    path = tmp_path / "w.counters"
    path.write_bytes(format_counters({7: 10}))
    calls: list[int] = []
    real = counter_module.parse_counters
    monkeypatch.setattr(counter_module, "parse_counters", lambda d: calls.append(1) or real(d))
    counters = CounterFile(path)
    counters.check()
    assert counters.reserve(7) == 11
    assert len(calls) == 2  # the file was new: read again under the lock
