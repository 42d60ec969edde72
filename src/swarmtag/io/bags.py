"""Reading a trial's event log out of a ROS 2 bag (rosbag2 sqlite3 or MCAP; the ``bags`` extra).

``read_bag`` opens a rosbag2 folder, a bare ``.db3`` file or an ``.mcap`` file (no ROS
installation needed): MCAP files by channel with Foxglove's ``mcap`` reader after checking
their CRCs (``swarmtag.io.mcap_in``), sqlite3 bags with ``rosbags``
(``swarmtag.io.bag_source``). It checks that the bag has every topic and field the mapping
(``swarmtag.io.bag_mapping``) names, reads the trial marks, tag changes and robot events of
those topics only, and turns them into the event logs of SPEC §8.1
(``swarmtag.io.bag_trials``). Message types come from the bag's own definitions; bags
without them (ROS 2 Humble's sqlite3 bags) are read with the Humble types plus
``swarmtag_msgs``.

Every refusal is one ``BagError`` line: a path that is no bag, a corrupt or damaged bag
(with the library's whole message, or the byte offset of a chunk failing its CRC), a topic
read short of the count the bag states, the topics and fields it lacks (all of them, in
one line), a value out of range (naming the topic, the message and the field), or a log
that breaks the event-log checks. Topics of service events or of foreign encodings are
never read and come back as ``BagLogs.skipped``.
"""

from __future__ import annotations

import functools
import math
import os
from collections.abc import Callable, Collection, Iterator, Sequence
from contextlib import ExitStack, contextmanager
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Final

import numpy as np

from swarmtag._inputs import check_path, regular_file
from swarmtag._interrupt import checkpoint
from swarmtag._resources import check_memory
from swarmtag.errors import BagError, SwarmtagError
from swarmtag.io.bag_mapping import BagMapping, FieldKind, Source
from swarmtag.io.bag_source import BagSource, RosbagsSource
from swarmtag.io.bag_trials import (
    RobotEvents,
    TagChanges,
    TrialMark,
    carrier_log,
    event_table,
    trials,
)
from swarmtag.io.mcap_check import one_line
from swarmtag.io.ros_types import require_rosbags, typestore
from swarmtag.io.schema import INT64_MAX, MISSING_ID
from swarmtag.io.tables import CarrierLog, EventTable
from swarmtag.tag import TagStatus

__all__ = ["BAG_SUFFIXES", "BYTES_PER_ENTRY", "BagLogs", "bag_path", "read_bag"]

BAG_SUFFIXES: Final = (".mcap", ".db3")
"""Bare storage files ``read_bag`` opens (besides rosbag2 folders with a ``metadata.yaml``)."""
BYTES_PER_ENTRY: Final = 300
"""Memory per trial mark, tag change or event kept while a bag is read (values, then arrays):
a margin over the measured peak, about 90 B (tracemalloc, 200,000 changes in 10-tag messages)."""
_CHECK_EVERY: Final = 1 << 16
_TIME: Final = "builtin_interfaces/msg/Time"
_INTEGERS: Final = frozenset(
    {"int8", "int16", "int32", "int64", "uint8", "uint16", "uint32", "uint64", "byte", "char"}
)
_FLOATS: Final = frozenset({"float32", "float64"})
_NAME, _BASE, _ARRAY, _SEQUENCE = 2, 1, 3, 4  # rosbags' Nodetype values


@dataclass(frozen=True, eq=False)
class BagLogs:
    """What a bag gave: the carrier log, the event table if asked for, trials, skipped topics.

    ``skipped``: topics not read because they hold no plain messages, ``topic (type: why)``.
    """

    carriers: CarrierLog
    events: EventTable | None
    trials: int
    skipped: tuple[str, ...] = ()


def bag_path(path: str | os.PathLike[str]) -> Path:
    """``path`` if it names a bag: a folder holding ``metadata.yaml``, or a storage file."""
    name = os.fspath(path)
    checked = check_path(path, what="bag", error=BagError)
    if checked.is_dir():
        if not (checked / "metadata.yaml").is_file():
            msg = f"{name}: a folder without metadata.yaml is no rosbag2 bag; give the bag's folder"
            raise BagError(msg)
        return checked
    found = regular_file(path, what="bag", error=BagError)
    if found.suffix.lower() not in BAG_SUFFIXES:
        msg = f"{name}: not a ROS 2 bag; give a rosbag2 folder, an .mcap or a .db3 file"
        raise BagError(msg)
    return found


# --- the bag's types: does it have what the mapping names? -----------------------------------


@dataclass(frozen=True, slots=True)
class _Leaf:
    """What a field path ends at: a base type or a message type, one value or a list."""

    name: str
    is_base: bool
    is_list: bool

    def describe(self) -> str:
        return f"{self.name}{'[]' if self.is_list else ''}"


def _leaf(fielddefs: Any, msgtype: str, path: Sequence[str]) -> _Leaf | None:  # noqa: ANN401
    """Follow ``path`` through the type definitions; None where a name is missing."""
    current = msgtype
    leaf = _Leaf(msgtype, is_base=False, is_list=False)
    for position, name in enumerate(path):
        if leaf.is_base or leaf.is_list or current not in fielddefs:
            return None
        fields = dict(fielddefs[current][1])
        if name not in fields:
            return None
        node, detail = fields[name]
        is_list = node in (_ARRAY, _SEQUENCE)
        if is_list:
            node, detail = detail[0]
        if node == _BASE:
            leaf = _Leaf(str(detail[0]), is_base=True, is_list=is_list)
        else:
            current = str(detail)
            leaf = _Leaf(current, is_base=False, is_list=is_list)
        if is_list and position < len(path) - 1:
            return None
    return leaf


def _fits(kind: FieldKind, leaf: _Leaf) -> bool:
    if not leaf.is_base or leaf.is_list != (kind in (FieldKind.INTS, FieldKind.NUMBERS)):
        return False
    if kind is FieldKind.TEXT:
        return leaf.name == "string"
    if kind in (FieldKind.INT, FieldKind.INTS):
        return leaf.name in _INTEGERS
    return leaf.name in _INTEGERS | _FLOATS


@dataclass(frozen=True, slots=True)
class _Topic:
    """A mapped topic to read: its name, type, stamp, entries and value sources by name."""

    key: str
    topic: str
    stamp: tuple[str, ...] | None
    entries: tuple[str, ...] | None
    message: dict[str, Source]
    entry: dict[str, Source]


def _problems(topic: _Topic, found: dict[str, str], fielddefs: Any) -> list[str]:  # noqa: ANN401
    """What ``topic`` lacks (missing topic, fields, wrong field types), in words."""
    msgtype = found.get(topic.topic)
    if msgtype is None:
        return [f"topic {topic.topic} ({topic.key} topic)"]
    if msgtype not in fielddefs:
        known = "the bag carries none, and it is no ROS 2 Humble or swarmtag_msgs type"
        return [f"the definition of {msgtype}, the type of {topic.topic} ({known})"]
    where = f"of {topic.topic} ({msgtype})"
    problems = []

    def check(path: Sequence[str], base: str, key: str, fits: Callable[[_Leaf], bool]) -> None:
        leaf = _leaf(fielddefs, base, path)
        dotted = ".".join(path)
        if leaf is None:
            problems.append(f"field {dotted} {where} ({key})")
        elif not fits(leaf):
            problems.append(f"field {dotted} {where} is {leaf.describe()}, not what {key} needs")

    if topic.stamp is not None:
        check(topic.stamp, msgtype, f"{topic.key} stamp", lambda x: x == _Leaf(_TIME, False, False))
    element = msgtype
    if topic.entries is not None:
        leaf = _leaf(fielddefs, msgtype, topic.entries)
        if leaf is None or leaf.is_base or not leaf.is_list:
            problems.append(
                f"field {'.'.join(topic.entries)} {where}, a list of messages ({topic.key} entries)"
            )
            return problems
        element = leaf.name
    for sources, base in ((topic.message, msgtype), (topic.entry, element)):
        for source in sources.values():
            if source.path:
                check(source.path, base, source.key, functools.partial(_fits, source.kind))
    return problems


def _topics(mapping: BagMapping, *, with_events: bool) -> dict[str, _Topic]:
    """The topics to read, by table name (``trial`` only where the mapping names a topic)."""
    trial, tags = mapping.trial, mapping.tag_status
    found = {}
    if trial.topic is not None:
        names = ("event", "condition", "run", "seed", "time_unit", "tick")
        sources = {n: getattr(trial, n) for n in (*names, "markers", "urgency0", "order_time")}
        message = {n: s for n, s in sources.items() if s is not None}
        found["trial"] = _Topic("[trial]", trial.topic, trial.stamp, None, message, {})
    entry = {n: getattr(tags, n) for n in ("marker", "status", "urgency", "robot")}
    found["tag_status"] = _Topic("[tag_status]", tags.topic, tags.stamp, tags.entries, {}, entry)
    events = mapping.robot_events
    if with_events and events is not None:
        values = {n: getattr(events, n) for n in ("kind", "robot", "carrier", "value")}
        entry = {n: s for n, s in values.items() if s is not None}
        found["robot_events"] = _Topic(
            "[robot_events]", events.topic, events.stamp, events.entries, {}, entry
        )
    return found


# --- reading values ------------------------------------------------------------------------------


def _get(message: object, path: Sequence[str]) -> Any:  # noqa: ANN401 - message fields are typed by the bag
    value: Any = message
    for name in path:
        value = getattr(value, name)
    return value


def _value(source: Source, message: object) -> Any:  # noqa: ANN401
    return _get(message, source.path) if source.path else source.fixed


class _Reading:
    """The messages of one bag being read: positions for messages, a memory bound."""

    def __init__(self, name: str, start: int) -> None:
        self.name, self.start, self.entries = name, start, 0

    def where(self, topic: str, index: int, at: int) -> str:
        return f"{topic} message {index + 1} ({(at - self.start) / 1e9:.3f} s into the bag)"

    def fail(self, where: str, problem: str) -> BagError:
        return BagError(f"{self.name}: {where}: {problem}")

    def count(self, added: int) -> None:
        """Note ``added`` kept values; refuse a bag whose kept values outgrow the memory limit."""
        before, self.entries = self.entries, self.entries + added
        if before // _CHECK_EVERY != self.entries // _CHECK_EVERY:
            checkpoint()
            check_memory(
                f"{self.name} ({self.entries} trial marks, tag changes and events)",
                self.entries * BYTES_PER_ENTRY,
                error=BagError,
            )

    def integer(self, source: Source, message: object, where: str, low: int, high: int) -> int:
        value = _value(source, message)
        number = int(value)
        if number != value or not low <= number <= high:
            raise self.fail(where, f"{source.key}: {value!r} is not an integer in {low}-{high}")
        return number

    def stamp(self, path: tuple[str, ...] | None, message: object, at: int) -> int:
        if path is None:
            return at
        time = _get(message, path)
        return int(time.sec) * 1_000_000_000 + int(time.nanosec)


def _text(reading: _Reading, source: Source, message: object, where: str) -> str:
    value = _value(source, message)
    if not isinstance(value, str):
        raise reading.fail(where, f"{source.key}: {value!r} is not text")
    return value


def _mark(
    reading: _Reading, mapping: BagMapping, message: object, at: int, where: str
) -> TrialMark:
    trial = mapping.trial
    starts = True
    if trial.event is not None:
        event = reading.integer(trial.event, message, where, -INT64_MAX - 1, INT64_MAX)
        if event not in (trial.start, trial.end):
            raise reading.fail(
                where, f"event {event} is neither start ({trial.start}) nor end ({trial.end})"
            )
        starts = event == trial.start
    if not starts:
        return TrialMark(time=at, starts=False, where=where)
    tick = float(_value(trial.tick, message))
    manifest = None
    if trial.markers is not None and trial.urgency0 is not None and trial.order_time is not None:
        markers = [int(m) for m in _value(trial.markers, message)]
        if markers:
            urgency = [int(u) for u in _value(trial.urgency0, message)]
            order = [float(t) for t in _value(trial.order_time, message)]
            bad = [u for u in urgency if not 0 <= u <= 9] + [m for m in markers if m < 0]
            if bad or not all(math.isfinite(t) for t in order):
                raise reading.fail(where, "urgency0 must be 0-9, markers >= 0, order_time finite")
            manifest = (tuple(markers), tuple(urgency), tuple(order))
    return TrialMark(
        time=at,
        starts=True,
        where=where,
        condition=_text(reading, trial.condition, message, where),
        run=reading.integer(trial.run, message, where, 0, INT64_MAX),
        seed=reading.integer(trial.seed, message, where, 0, INT64_MAX),
        time_unit=_text(reading, trial.time_unit, message, where),
        tick=tick,
        markers=None if manifest is None else manifest[0],
        urgency0=None if manifest is None else manifest[1],
        order_time=None if manifest is None else manifest[2],
    )


def _entries(topic: _Topic, message: object) -> list[object]:
    return [message] if topic.entries is None else list(_get(message, topic.entries))


def _read_marks(reader: BagSource, mapping: BagMapping, reading: _Reading) -> list[TrialMark]:
    topic = mapping.trial.topic
    if topic is None:
        return [
            _mark(reading, mapping, None, reading.start, f"the bag's one trial ({mapping.source})")
        ]
    marks = []
    for index, at, message in reader.messages(topic):
        reading.count(1)
        stamp = reading.stamp(mapping.trial.stamp, message, at)
        marks.append(_mark(reading, mapping, message, stamp, reading.where(topic, index, stamp)))
    return marks


def _read_changes(
    reader: BagSource, mapping: BagMapping, topic: _Topic, reading: _Reading
) -> TagChanges:
    tags = mapping.tag_status
    codes = {
        tags.idle: TagStatus.IDLE,
        tags.awaiting_pickup: TagStatus.AWAITING_PICKUP,
        tags.picked_up: TagStatus.PICKED_UP,
    }
    columns: list[list[int]] = [[], [], [], [], []]
    for index, at, message in reader.messages(topic.topic):
        stamp = reading.stamp(topic.stamp, message, at)
        where = reading.where(topic.topic, index, stamp)
        entries = _entries(topic, message)
        reading.count(len(entries))
        for entry in entries:
            status = reading.integer(tags.status, entry, where, -INT64_MAX - 1, INT64_MAX)
            if status not in codes:
                shown = ", ".join(f"{v.name.lower()} {k}" for k, v in codes.items())
                raise reading.fail(
                    where, f"status {status} is none of {shown} ([tag_status] values)"
                )
            robot = reading.integer(tags.robot, entry, where, -INT64_MAX - 1, INT64_MAX)
            columns[0].append(stamp)
            columns[1].append(reading.integer(tags.marker, entry, where, 0, INT64_MAX))
            columns[2].append(int(codes[status]))
            columns[3].append(reading.integer(tags.urgency, entry, where, 0, 9))
            columns[4].append(max(robot, MISSING_ID))
    arrays = [np.array(column, dtype=np.int64) for column in columns]
    return TagChanges(
        time=arrays[0], marker=arrays[1], status=arrays[2], urgency=arrays[3], robot=arrays[4]
    )


def _read_events(
    reader: BagSource, mapping: BagMapping, topic: _Topic, reading: _Reading
) -> RobotEvents:
    events = mapping.robot_events
    assert events is not None
    times: list[int] = []
    kinds: list[str] = []
    ids: list[list[int]] = [[], []]
    values: list[float] = []
    for index, at, message in reader.messages(topic.topic):
        stamp = reading.stamp(topic.stamp, message, at)
        where = reading.where(topic.topic, index, stamp)
        entries = _entries(topic, message)
        reading.count(len(entries))
        for entry in entries:
            times.append(stamp)
            kinds.append(_text(reading, events.kind, entry, where))
            for column, source in zip(ids, (events.robot, events.carrier), strict=True):
                number = (
                    MISSING_ID
                    if source is None
                    else reading.integer(source, entry, where, -INT64_MAX - 1, INT64_MAX)
                )
                column.append(max(number, MISSING_ID))
            values.append(math.nan if events.value is None else float(_value(events.value, entry)))
    return RobotEvents(
        time=np.array(times, dtype=np.int64),
        kind=kinds,
        robot=np.array(ids[0], dtype=np.int64),
        carrier=np.array(ids[1], dtype=np.int64),
        value=np.array(values, dtype=np.float64),
    )


@contextmanager
def _bag_errors(name: str) -> Iterator[None]:
    """Whatever the storage libraries raise on a corrupt file, as one ``BagError`` line.

    The library's whole message is kept, its lines joined into one.
    """
    try:
        yield
    except SwarmtagError:
        raise
    except MemoryError:
        msg = f"{name}: too large to read (out of memory)"
        raise BagError(msg) from None
    except Exception as error:  # noqa: BLE001 - the storage libraries raise many kinds
        msg = f"{name}: not a readable ROS 2 bag ({one_line(error)})"
        raise BagError(msg) from None


def _open(bag: Path, name: str, needed: Collection[str], stack: ExitStack) -> BagSource:
    """The bag's reader: MCAP files by channel, anything else through ``rosbags``."""
    from rosbags.highlevel import AnyReader  # noqa: PLC0415 - the bags extra

    from swarmtag.io.bag_metadata import read_metadata  # noqa: PLC0415
    from swarmtag.io.mcap_in import McapSource  # noqa: PLC0415

    if bag.is_dir():
        metadata = read_metadata(bag, name)
        if metadata.storage == "mcap" and not metadata.compression:
            return McapSource(name, metadata.files, needed, stack, metadata.counts)
    elif bag.suffix.lower() == ".mcap":
        return McapSource(name, [bag], needed, stack)
    reader = stack.enter_context(AnyReader([bag], default_typestore=typestore()))
    return RosbagsSource(name, reader, folder=bag.is_dir())


def read_bag(
    path: str | os.PathLike[str], mapping: BagMapping | None = None, *, with_events: bool = False
) -> BagLogs:
    """The event log (and, ``with_events``, the event table) of every trial in a bag.

    ``mapping`` defaults to the shipped ``swarmtag_msgs`` mapping.
    """
    mapping = BagMapping.default() if mapping is None else mapping
    if with_events and mapping.robot_events is None:
        msg = f"{mapping.source}: has no [robot_events] table; an event table needs one"
        raise BagError(msg)
    bag = bag_path(path)
    name = os.fspath(path)
    require_rosbags()
    topics = _topics(mapping, with_events=with_events)
    needed = {t.topic for t in topics.values()}
    with _bag_errors(name), ExitStack() as stack:
        reader = _open(bag, name, needed, stack)
        found = reader.topics
        problems = [p for t in topics.values() for p in _problems(t, found, reader.fielddefs)]
        if problems:
            listed = ", ".join(f"{t} ({m})" for t, m in sorted(found.items())) or "none"
            msg = (
                f"{name}: lacks what the mapping {mapping.source} names: {'; '.join(problems)}. "
                f"The bag's topics: {listed}"
            )
            raise BagError(msg)
        reading = _Reading(name, reader.start)
        found_trials = trials(_read_marks(reader, mapping, reading), source=name)
        start = min(reader.start, found_trials[0].start)  # trials are named by their time from here
        changes = _read_changes(reader, mapping, topics["tag_status"], reading)
        events = (
            _read_events(reader, mapping, topics["robot_events"], reading) if with_events else None
        )
    log = carrier_log(found_trials, changes, source=name, bag_start=start)
    if len(log) == 0:
        msg = f"{name}: no carrier was ordered in any of its {len(found_trials)} trial(s)"
        raise BagError(msg)
    table = None
    if events is not None:
        table = event_table(found_trials, events, source=name, bag_start=start)
    return BagLogs(carriers=log, events=table, trials=len(found_trials), skipped=reader.skipped)
