"""The topic and field mapping of a ROS 2 bag: where a trial's start, tag states and events are.

A mapping is a TOML file (format 1, documented in docs/trial-logs.md) with three tables:
``[trial]`` (trial start and end messages: condition, run, seed, time unit, optionally the
carriers with their urgency and order time), ``[tag_status]`` (tag state changes: marker,
status, urgency, the robot that wrote it) and the optional ``[robot_events]`` (the
long-format event table). Each value names a field path in the message (entries' fields
are relative to the entry) or gives a fixed value, ``{ value = ... }``. The default mapping,
shipped as ``swarmtag/data/bag_mapping.toml``, describes the ``swarmtag_msgs`` layout.

Reading a mapping checks its keys and the types of fixed values; whether a bag has the
topics and fields is checked when the bag is opened (``swarmtag.io.bags``). Every refusal is
one ``BagError`` naming the file and the key.

>>> mapping = BagMapping.default()
>>> mapping.trial.topic, mapping.tag_status.entries, mapping.tag_status.robot.path
('/swarmtag/trial', ('tags',), ('robot',))
"""

from __future__ import annotations

import enum
import math
import os
import re
from dataclasses import dataclass
from importlib.resources import files
from importlib.resources.abc import Traversable
from typing import Any, Final, NoReturn

from swarmtag._toml import loads_toml, read_toml
from swarmtag.errors import BagError

__all__ = [
    "DEFAULT_MAPPING",
    "LOG_TIME",
    "MAPPING_FORMAT",
    "BagMapping",
    "EventMapping",
    "FieldKind",
    "Source",
    "TagMapping",
    "TrialMapping",
    "default_mapping",
]

MAPPING_FORMAT: Final = 1
"""The mapping format this version reads (the ``format`` key)."""
DEFAULT_MAPPING: Final = "bag_mapping.toml"
"""File name of the default mapping inside ``swarmtag.data``."""
LOG_TIME: Final = "@log"
"""A ``stamp`` naming the time the bag recorded each message instead of a field."""
_PATH: Final = re.compile(r"[A-Za-z_][A-Za-z0-9_]*(?:\.[A-Za-z_][A-Za-z0-9_]*)*")


class FieldKind(enum.Enum):
    """What a mapped value must be; the value is the word used in messages."""

    TEXT = "text"
    INT = "an integer"
    NUMBER = "a number"
    INTS = "a list of integers"
    NUMBERS = "a list of numbers"


@dataclass(frozen=True, slots=True)
class Source:
    """Where one value comes from: a field ``path`` in the message (or entry), else ``fixed``.

    ``key`` names it in messages (``[trial] condition``).
    """

    key: str
    kind: FieldKind
    path: tuple[str, ...] = ()
    fixed: Any = None

    @property
    def dotted(self) -> str:
        """The field path as written in the mapping: ``header.stamp``."""
        return ".".join(self.path)


@dataclass(frozen=True, slots=True)
class TrialMapping:
    """Trial start and end messages (``topic`` None: the bag is one trial, from its first message).

    ``stamp`` is the path of a ``builtin_interfaces/Time`` field, or None for the log time.
    Without ``event`` every message starts a trial. ``markers``, ``urgency0`` and
    ``order_time`` (all or none) list the trial's carriers.
    """

    topic: str | None
    stamp: tuple[str, ...] | None
    event: Source | None
    start: int
    end: int
    condition: Source
    run: Source
    seed: Source
    time_unit: Source
    tick: Source
    markers: Source | None
    urgency0: Source | None
    order_time: Source | None


@dataclass(frozen=True, slots=True)
class TagMapping:
    """Tag state changes: one per message, or a list of them at ``entries``.

    ``idle``, ``awaiting_pickup`` and ``picked_up`` are the status values the bag uses.
    """

    topic: str
    stamp: tuple[str, ...] | None
    entries: tuple[str, ...] | None
    marker: Source
    status: Source
    urgency: Source
    robot: Source
    idle: int
    awaiting_pickup: int
    picked_up: int


@dataclass(frozen=True, slots=True)
class EventMapping:
    """Robot events for the long-format event table: one per message, or a list at ``entries``."""

    topic: str
    stamp: tuple[str, ...] | None
    entries: tuple[str, ...] | None
    kind: Source
    robot: Source | None
    carrier: Source | None
    value: Source | None


_KEYS: Final[dict[str, dict[str, FieldKind | str]]] = {
    "trial": {
        "topic": "topic",
        "stamp": "stamp",
        "event": FieldKind.INT,
        "start": "code",
        "end": "code",
        "condition": FieldKind.TEXT,
        "run": FieldKind.INT,
        "seed": FieldKind.INT,
        "time_unit": FieldKind.TEXT,
        "tick": FieldKind.NUMBER,
        "markers": FieldKind.INTS,
        "urgency0": FieldKind.INTS,
        "order_time": FieldKind.NUMBERS,
    },
    "tag_status": {
        "topic": "topic",
        "stamp": "stamp",
        "entries": "entries",
        "marker": FieldKind.INT,
        "status": FieldKind.INT,
        "urgency": FieldKind.INT,
        "robot": FieldKind.INT,
        "idle": "code",
        "awaiting_pickup": "code",
        "picked_up": "code",
    },
    "robot_events": {
        "topic": "topic",
        "stamp": "stamp",
        "entries": "entries",
        "kind": FieldKind.TEXT,
        "robot": FieldKind.INT,
        "carrier": FieldKind.INT,
        "value": FieldKind.NUMBER,
    },
}
"""Every key of every table, with what it holds (a ``FieldKind`` source, or a plain key)."""
_REQUIRED: Final = {
    "trial": ("condition", "run", "seed"),
    "tag_status": ("topic", "marker", "status", "urgency", "robot"),
    "robot_events": ("topic", "kind"),
}
_MANIFEST: Final = ("markers", "urgency0", "order_time")


def _is_int(value: object) -> bool:
    return isinstance(value, int) and not isinstance(value, bool)


def _is_number(value: object) -> bool:
    return (_is_int(value) or isinstance(value, float)) and math.isfinite(float(value))  # type: ignore[arg-type]


def _fits(kind: FieldKind, value: object) -> bool:
    """Whether a fixed ``value`` from TOML is of ``kind`` (ranges are checked on conversion)."""
    if kind is FieldKind.TEXT:
        return isinstance(value, str)
    if kind is FieldKind.INT:
        return _is_int(value)
    if kind is FieldKind.NUMBER:
        return _is_number(value)
    check = _is_int if kind is FieldKind.INTS else _is_number
    return isinstance(value, list) and all(check(item) for item in value)


class _Table:
    """One table of a mapping file being read: its keys, refused with the file and key named."""

    def __init__(self, source: str, name: str, data: object) -> None:
        self.origin, self.name = source, name
        if not isinstance(data, dict):
            self.fail(f"[{name}] must be a table")
        self.data: dict[str, Any] = dict(data)
        unknown = sorted(set(data) - set(_KEYS[name]))
        if unknown:
            self.fail(f"[{name}] has no key {unknown[0]!r}; its keys are {', '.join(_KEYS[name])}")
        missing = [key for key in _REQUIRED[name] if key not in data]
        if missing:
            self.fail(f"[{name}] lacks {', '.join(missing)}")

    def fail(self, problem: str) -> NoReturn:
        msg = f"{self.origin}: {problem}"
        raise BagError(msg)

    def path(self, key: str, text: object) -> tuple[str, ...]:
        if not isinstance(text, str) or not _PATH.fullmatch(text):
            self.fail(
                f"[{self.name}] {key}: {text!r} is not a field path "
                "(names joined by dots, e.g. header.stamp)"
            )
        return tuple(text.split("."))

    def topic(self, *, required: bool = True) -> str | None:
        text = self.data.get("topic")
        if text is None and not required:
            return None
        if not isinstance(text, str) or not text.startswith("/") or not text.isprintable():
            self.fail(f"[{self.name}] topic: {text!r} is not a topic name (e.g. /swarmtag/trial)")
        return text

    def stamp(self) -> tuple[str, ...] | None:
        text = self.data.get("stamp", "header.stamp")
        return None if text == LOG_TIME else self.path("stamp", text)

    def entries(self) -> tuple[str, ...] | None:
        text = self.data.get("entries")
        return None if text is None else self.path("entries", text)

    def code(self, key: str, default: int) -> int:
        value: object = self.data.get(key, default)
        if not isinstance(value, int) or isinstance(value, bool):
            self.fail(f"[{self.name}] {key}: {value!r} is not an integer")
        return value

    def source(self, key: str, *, fields: bool = True) -> Source | None:
        """The source of ``key``: a field path or ``{ value = ... }``; None if absent."""
        kind = _KEYS[self.name][key]
        assert isinstance(kind, FieldKind)
        where = f"[{self.name}] {key}"
        given = self.data.get(key)
        if given is None:
            return None
        if isinstance(given, dict):
            if set(given) != {"value"}:
                self.fail(f"{where}: a fixed value is written {{ value = ... }}")
            if not _fits(kind, given["value"]):
                self.fail(f"{where}: {given['value']!r} is not {kind.value}")
            return Source(where, kind, fixed=given["value"])
        if not fields:
            self.fail(
                f"{where}: {given!r} names a field, but [trial] has no topic; "
                "give a fixed value, { value = ... }"
            )
        return Source(where, kind, path=self.path(key, given))

    def required(self, key: str, *, fields: bool = True) -> Source:
        found = self.source(key, fields=fields)
        assert found is not None  # required keys were checked on construction
        return found

    def defaulted(self, key: str, default: object, *, fields: bool = True) -> Source:
        """The source of ``key``, or the fixed ``default`` where the key is absent."""
        found = self.source(key, fields=fields)
        if found is not None:
            return found
        kind = _KEYS[self.name][key]
        assert isinstance(kind, FieldKind)
        return Source(f"[{self.name}] {key}", kind, fixed=default)

    def distinct(self, keys: tuple[str, ...], values: tuple[int, ...]) -> None:
        if len(set(values)) < len(values):
            self.fail(f"[{self.name}] {', '.join(keys)} must be different values")


def _trial(table: _Table) -> TrialMapping:
    topic = table.topic(required=False)
    fields = topic is not None
    manifest = [table.source(key, fields=fields) for key in _MANIFEST]
    if any(m is None for m in manifest) and any(m is not None for m in manifest):
        table.fail("[trial] markers, urgency0 and order_time go together: give all three or none")
    start, end = table.code("start", 0), table.code("end", 1)
    table.distinct(("start", "end"), (start, end))
    return TrialMapping(
        topic=topic,
        stamp=table.stamp() if fields else None,
        event=table.source("event", fields=fields),
        start=start,
        end=end,
        condition=table.required("condition", fields=fields),
        run=table.required("run", fields=fields),
        seed=table.required("seed", fields=fields),
        time_unit=table.defaulted("time_unit", "s", fields=fields),
        tick=table.defaulted("tick", 0.0, fields=fields),
        markers=manifest[0],
        urgency0=manifest[1],
        order_time=manifest[2],
    )


def _tags(table: _Table) -> TagMapping:
    codes = tuple(
        table.code(key, n) for n, key in enumerate(("idle", "awaiting_pickup", "picked_up"))
    )
    table.distinct(("idle", "awaiting_pickup", "picked_up"), codes)
    topic = table.topic()
    assert topic is not None
    return TagMapping(
        topic=topic,
        stamp=table.stamp(),
        entries=table.entries(),
        marker=table.required("marker"),
        status=table.required("status"),
        urgency=table.required("urgency"),
        robot=table.required("robot"),
        idle=codes[0],
        awaiting_pickup=codes[1],
        picked_up=codes[2],
    )


def _events(table: _Table) -> EventMapping:
    topic = table.topic()
    assert topic is not None
    return EventMapping(
        topic=topic,
        stamp=table.stamp(),
        entries=table.entries(),
        kind=table.required("kind"),
        robot=table.source("robot"),
        carrier=table.source("carrier"),
        value=table.source("value"),
    )


@dataclass(frozen=True, slots=True)
class BagMapping:
    """A checked mapping: ``trial``, ``tag_status`` and optionally ``robot_events``.

    ``source`` names the file it came from in messages.
    """

    trial: TrialMapping
    tag_status: TagMapping
    robot_events: EventMapping | None
    source: str

    @classmethod
    def from_mapping(cls, data: dict[str, Any], *, source: str) -> BagMapping:
        """Check a parsed TOML mapping; ``BagError`` names ``source`` and the key at fault."""
        unknown = sorted(set(data) - {"format", *_KEYS})
        if unknown:
            msg = f"{source}: unknown key or table {unknown[0]!r}; expected format, " + ", ".join(
                f"[{name}]" for name in _KEYS
            )
            raise BagError(msg)
        if data.get("format") != MAPPING_FORMAT:
            msg = (
                f"{source}: format {data.get('format')!r} is not {MAPPING_FORMAT}; write format = 1"
            )
            raise BagError(msg)
        for name in ("trial", "tag_status"):
            if name not in data:
                msg = f"{source}: the [{name}] table is missing"
                raise BagError(msg)
        events = data.get("robot_events")
        return cls(
            trial=_trial(_Table(source, "trial", data["trial"])),
            tag_status=_tags(_Table(source, "tag_status", data["tag_status"])),
            robot_events=None
            if events is None
            else _events(_Table(source, "robot_events", events)),
            source=source,
        )

    @classmethod
    def load(cls, path: str | os.PathLike[str]) -> BagMapping:
        """Read and check a mapping file."""
        data = read_toml(path, what="bag mapping", error=BagError)
        return cls.from_mapping(data, source=os.fspath(path))

    @classmethod
    def default(cls) -> BagMapping:
        """The shipped mapping of the ``swarmtag_msgs`` layout."""
        text = default_mapping().read_text(encoding="utf-8")
        return cls.from_mapping(
            loads_toml(text, source=DEFAULT_MAPPING, error=BagError), source=DEFAULT_MAPPING
        )


def default_mapping() -> Traversable:
    """The shipped default mapping as an ``importlib.resources`` resource (copy it to adapt)."""
    return files("swarmtag.data").joinpath(DEFAULT_MAPPING)
