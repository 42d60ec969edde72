"""Every public callable of ``swarmtag.tag``, called with arbitrary Python values.

Only ``SwarmtagError`` subclasses may escape (or the call succeeds with a
result of the documented type); ``ScanFilter.feed`` may not raise at all. A
completeness check makes sure a new public callable cannot skip the sweep.
"""

from __future__ import annotations

import contextlib
import inspect
import os
import tempfile
from collections import Counter
from collections.abc import Callable
from pathlib import Path

import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st

import swarmtag.tag
from swarmtag.errors import SwarmtagError
from swarmtag.tag import (
    Change,
    FileStore,
    MemoryStore,
    Role,
    ScanFilter,
    TagModel,
    TagRecord,
    TagState,
    TagStatus,
    Write,
    WriterKey,
    WriteSigner,
    apply_change,
    decode,
    decode_manufacturer_data,
    derive_robot_key,
    derive_role_key,
    encode,
    encode_manufacturer_data,
    read_key_file,
    read_role_key_file,
    read_writer_key_file,
    sign,
    verify,
    write_key_file,
    write_robot_key_file,
    write_role_key_file,
)
from swarmtag.tag.claim import Claim
from tests.strategies import changes, tag_states

KEY = bytes(range(16))  # the site key
ROLE_KEYS = {role: derive_role_key(KEY, role) for role in Role}
MARKER = 12
START = TagState(urgency=3, status=TagStatus.AWAITING_PICKUP, destination=0, marker=MARKER)

writes = st.builds(
    Write,
    writer=st.integers(0, 0xFFFF),
    role=st.sampled_from(Role),
    counter=st.integers(0, 2**32 - 1),
    target=st.sampled_from([MARKER, 0, 255]),
    change=changes,
)
records = st.builds(
    TagRecord,
    state=tag_states,
    counters=st.dictionaries(st.integers(0, 0xFFFF), st.integers(0, 2**32 - 1), max_size=3),
    shared_robot_key=st.booleans(),
)


def _writer_key(write: Write) -> bytes:
    """The key a tag checks ``write`` under: the robot's own, or the operator key."""
    return (
        derive_robot_key(KEY, write.writer) if write.role is Role.ROBOT else ROLE_KEYS[write.role]
    )


def _stored(record: TagRecord) -> MemoryStore:
    store = MemoryStore()
    store.save(record.to_bytes())
    return store


# Arbitrary values, plus valid objects of every kind so that calls reach past the first check.
hostile = st.one_of(
    st.none(),
    st.booleans(),
    st.integers(),
    st.sampled_from([-1, 10, 256, 2**16, 2**32, 2**64, 10**5000, -(10**5000)]),
    st.floats(),  # nan and infinities included
    st.text(max_size=24),
    st.binary(max_size=24),
    st.builds(bytearray, st.binary(max_size=24)),
    st.builds(memoryview, st.binary(max_size=24)),
    st.lists(st.integers(-300, 300), max_size=24),
    st.dictionaries(
        st.integers(-1, 0x10000) | st.text(max_size=3),
        st.binary(max_size=6) | st.integers() | st.none(),
        max_size=3,
    ),
    st.builds(Counter, st.dictionaries(st.text(max_size=4), st.integers(), max_size=2)),
    st.builds(Path, st.text(max_size=12)),
    st.sampled_from(TagStatus),
    st.sampled_from(Role),
    st.just(KEY),
    st.sampled_from(list(ROLE_KEYS.values())),  # 32 bytes: a role key, or a key file's key
    tag_states,
    changes,
    writes,
    records,
    writes.map(lambda write: sign(write, _writer_key(write))),  # authentic 20-byte writes
    tag_states.map(encode),  # valid advertisements
    tag_states.map(encode_manufacturer_data),
    st.builds(MemoryStore),
    records.map(_stored),
)


def _claim(message: object, now: object) -> Claim:
    """Claim a fresh tag; a refusal must leave its counters, store and claim as they were."""
    store = MemoryStore()
    tag = TagModel.provision(START, site_key=KEY, store=store)
    before = store.load()
    try:
        return tag.claim(message, now=now)  # type: ignore[arg-type]
    except SwarmtagError:
        assert (dict(tag.counters), store.load(), tag.claim_at(0.0)) == ({}, before, None)
        raise


def _apply(message: object) -> TagState:
    """Apply to a fresh tag; a refusal must leave state, counters and store as they were."""
    store = MemoryStore()
    tag = TagModel.provision(START, site_key=KEY, store=store)
    before = store.load()
    try:
        return tag.apply(message)
    except SwarmtagError:
        assert (tag.state, dict(tag.counters), store.load()) == (START, {}, before)
        raise


def _file_store(path: object) -> FileStore:
    """Construct in a scratch folder, so relative paths touch nothing real."""
    with tempfile.TemporaryDirectory() as folder, contextlib.chdir(folder):
        return FileStore(path)


def _file_store_save(record: object) -> None:
    with tempfile.TemporaryDirectory() as folder:
        store = FileStore(Path(folder) / "tag.bin")
        store.save(record)
        assert store.load() == bytes(record)


def _signer_sign(target: object, change: object) -> bytes:
    signer = WriteSigner(writer=1, role=Role.OPERATOR, key=ROLE_KEYS[Role.OPERATOR])
    try:
        return signer.sign(target, change)
    except SwarmtagError:
        assert signer.counter == -1  # a refused argument does not use up a counter
        raise


def _stays_in_scratch(path: object) -> bool:
    """False for a path that could reach outside the scratch folder (absolute, or '..')."""
    text = os.fspath(path) if isinstance(path, str | os.PathLike) else None
    return not isinstance(text, str) or not (Path(text).is_absolute() or ".." in Path(text).parts)


def _in_scratch(call: Callable[..., object]) -> Callable[..., object]:
    """``call`` run in a fresh scratch folder, for paths that stay inside it."""

    def scratch(path: object, *args: object) -> object:
        assume(_stays_in_scratch(path))
        with tempfile.TemporaryDirectory() as folder, contextlib.chdir(folder):
            return call(path, *args)

    return scratch


# name -> (call taking positional arguments, number of arguments, type of a successful result)
TARGETS: dict[str, tuple[Callable[..., object], int, type | tuple[type, ...]]] = {
    "Change": (lambda u, s, d: Change(urgency=u, status=s, destination=d), 3, Change),
    "FileStore": (_file_store, 1, FileStore),
    "FileStore.save": (_file_store_save, 1, type(None)),
    "MemoryStore.save": (lambda r: MemoryStore().save(r), 1, type(None)),
    "Role": (Role, 1, Role),
    "ScanFilter": (lambda a, f, e: ScanFilter(accepted=a, foreign=f, errors=e), 3, ScanFilter),
    "ScanFilter.feed": (lambda data: ScanFilter().feed(data), 1, (TagState, type(None))),
    "TagModel": (lambda r, k, s: TagModel(r, site_key=k, store=s), 3, TagModel),
    "TagModel.apply": (_apply, 1, TagState),
    "TagModel.claim": (_claim, 2, Claim),
    "TagModel.claim_at": (
        lambda now: TagModel.provision(START, site_key=KEY, store=MemoryStore()).claim_at(now),
        1,
        type(None),
    ),
    "TagModel.boot": (lambda k, s: TagModel.boot(site_key=k, store=s), 2, TagModel),
    "TagModel.provision": (
        lambda st_, k, s, b: TagModel.provision(st_, site_key=k, store=s, shared_robot_key=b),
        4,
        TagModel,
    ),
    "TagModel.set_shared_robot_key": (
        lambda b: TagModel.provision(START, site_key=KEY, store=MemoryStore()).set_shared_robot_key(
            b
        ),
        1,
        type(None),
    ),
    "TagRecord": (
        lambda s, c, lifter, b: TagRecord(state=s, counters=c, lifter=lifter, shared_robot_key=b),
        4,
        TagRecord,
    ),
    "TagRecord.from_bytes": (TagRecord.from_bytes, 1, TagRecord),
    "TagState": (
        lambda u, s, d, m: TagState(urgency=u, status=s, destination=d, marker=m),
        4,
        TagState,
    ),
    "TagStatus": (TagStatus, 1, TagStatus),
    "TagStatus.parse": (TagStatus.parse, 1, TagStatus),
    "Write": (
        lambda w, r, n, t, c: Write(writer=w, role=r, counter=n, target=t, change=c),
        5,
        Write,
    ),
    "WriteSigner": (
        lambda w, r, k, n: WriteSigner(writer=w, role=r, key=k, counter=n),
        4,
        WriteSigner,
    ),
    "WriteSigner.sign": (_signer_sign, 2, bytes),
    "WriterKey": (lambda r, k, w: WriterKey(role=r, key=k, writer=w), 3, WriterKey),
    "WriterKey.writer_id": (
        lambda w, p: WriterKey(role=Role.ROBOT, key=bytes(32), writer=7).writer_id(w, p),
        2,
        int,
    ),
    "apply_change": (apply_change, 3, TagState),
    "decode": (decode, 1, TagState),
    "decode_manufacturer_data": (decode_manufacturer_data, 1, TagState),
    "encode": (encode, 1, bytes),
    "derive_role_key": (derive_role_key, 2, bytes),
    "derive_robot_key": (derive_robot_key, 2, bytes),
    "encode_manufacturer_data": (encode_manufacturer_data, 1, dict),
    "read_key_file": (_in_scratch(read_key_file), 1, bytes),
    "write_key_file": (_in_scratch(write_key_file), 2, Path),
    "read_role_key_file": (_in_scratch(read_role_key_file), 1, tuple),
    "write_role_key_file": (_in_scratch(write_role_key_file), 3, Path),
    "read_writer_key_file": (_in_scratch(read_writer_key_file), 1, WriterKey),
    "write_robot_key_file": (_in_scratch(write_robot_key_file), 3, Path),
    "sign": (sign, 2, bytes),
    "verify": (verify, 2, Write),
}

NOT_SWEPT = {
    "MemoryStore": "takes no arguments",
    "generate_site_key": "takes no arguments",
    "TagStore": "a typing.Protocol: describes stores, is never called",
    "TagStore.save": "a Protocol method without a body",
}


def _public_callables() -> set[str]:
    """Public callables of swarmtag.tag and the public methods (with parameters) of its classes."""
    names = set()
    for name in swarmtag.tag.__all__:
        value = getattr(swarmtag.tag, name)
        if not callable(value):
            continue
        names.add(name)
        if not isinstance(value, type):
            continue
        for attr, member in vars(value).items():
            function = getattr(member, "__func__", member)
            if attr.startswith("_") or not inspect.isfunction(function):
                continue
            if len(inspect.signature(function).parameters) > 1:  # beyond self / cls
                names.add(f"{name}.{attr}")
    return names


def test_every_public_callable_is_swept():
    assert _public_callables() == set(TARGETS) | set(NOT_SWEPT)
    assert {"TagModel.apply", "WriteSigner.sign", "TagStatus.parse"} <= set(TARGETS)


@pytest.mark.parametrize("name", sorted(TARGETS))
@settings(max_examples=60, deadline=None)
@given(data=st.data())
def test_only_swarmtag_errors_escape(name, data):
    call, arity, result_type = TARGETS[name]
    args = data.draw(st.tuples(*[hostile] * arity), label="args")
    try:
        result = call(*args)
    except SwarmtagError:
        assert name != "ScanFilter.feed", "ScanFilter.feed must never raise"
        return
    assert isinstance(result, result_type)
    if name == "encode":
        assert len(result) == 6
    if name in {"sign", "WriteSigner.sign"}:
        assert len(result) == 20
