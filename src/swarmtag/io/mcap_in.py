"""MCAP bags read by channel with Foxglove's ``mcap`` reader (the ``bags`` extra).

``McapSource`` opens one bare ``.mcap`` file or the MCAP files of a rosbag2 folder. Each
file's CRCs are verified first (``swarmtag.io.mcap_check``); then only the channels of the
topics asked for are looked at: their schemas alone are parsed (``ros2msg`` or ``ros2idl``,
into a ``rosbags`` type store on top of the ROS 2 Humble and ``swarmtag_msgs`` types), and
their messages alone are read, in log-time order. Channels of other topics are never parsed,
so a service-event or foreign-encoded channel cannot stop an import; those are reported as
skipped. Channels are matched by topic only (not by QoS), and each topic read is held against
the file's statistics record (``channel_message_counts``) and the folder's ``metadata.yaml``.
"""

from __future__ import annotations

from collections.abc import Collection, Iterator, Sequence
from contextlib import ExitStack
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any, Final

from mcap.reader import SeekingReader, make_reader
from mcap.records import Channel, Chunk, Message, Schema
from mcap.stream_reader import StreamReader, breakup_chunk

from swarmtag.errors import BagError
from swarmtag.io.bag_source import BagSource, not_messages
from swarmtag.io.mcap_check import one_line, verify_mcap
from swarmtag.io.ros_types import typestore

if TYPE_CHECKING:
    from rosbags.typesys.store import Typestore

__all__ = ["McapSource"]

_IDL_SEPARATOR: Final = "=" * 80 + "\n"
_DEFINITIONS: Final = ("ros2msg", "ros2idl", "")


@dataclass
class _File:
    """One open MCAP file: its reader, schemas, channels, counts (None: no statistics)."""

    label: str
    reader: SeekingReader
    schemas: dict[int, Schema]
    channels: dict[int, Channel]
    counts: dict[int, int] | None
    start: int | None
    by_topic: dict[str, list[Channel]] = field(default_factory=dict)


def _scan(path: Path) -> tuple[dict[int, Schema], dict[int, Channel], int | None]:
    """Schemas, channels and first log time of a file without a summary (one linear read)."""
    schemas: dict[int, Schema] = {}
    channels: dict[int, Channel] = {}
    start: int | None = None
    with path.open("rb") as handle:
        for record in StreamReader(handle, emit_chunks=True).records:
            inner = breakup_chunk(record) if isinstance(record, Chunk) else [record]
            for item in inner:
                if isinstance(item, Schema):
                    schemas[item.id] = item
                elif isinstance(item, Channel):
                    channels[item.id] = item
                elif isinstance(item, Message):
                    start = item.log_time if start is None else min(start, item.log_time)
    return schemas, channels, start


def _open(path: Path, label: str, stack: ExitStack) -> _File:
    handle = stack.enter_context(path.open("rb"))
    reader = make_reader(handle, validate_crcs=True)
    assert isinstance(reader, SeekingReader)  # a file can seek
    summary = reader.get_summary()
    if summary is None:
        schemas, channels, start = _scan(path)
        counts = None
    else:
        schemas, channels = dict(summary.schemas), dict(summary.channels)
        stats = summary.statistics
        counts = None if stats is None else dict(stats.channel_message_counts)
        if stats is not None and stats.message_count:
            start = stats.message_start_time
        else:
            starts = [c.message_start_time for c in summary.chunk_indexes]
            start = min(starts) if starts else None
    opened = _File(label, reader, schemas, channels, counts, start)
    for channel in sorted(channels.values(), key=lambda c: c.id):
        opened.by_topic.setdefault(channel.topic, []).append(channel)
    return opened


def _types(schema: Schema) -> dict[str, Any]:
    """The type definitions a ROS 2 schema holds (itself and the types it embeds)."""
    from rosbags.typesys import get_types_from_idl, get_types_from_msg  # noqa: PLC0415

    text = schema.data.decode("utf-8")
    if schema.encoding == "ros2msg":
        return dict(get_types_from_msg(text, schema.name))
    found: dict[str, Any] = {}
    if text.startswith(f"{_IDL_SEPARATOR}IDL: "):
        for part in text.split(_IDL_SEPARATOR)[1:]:
            found.update(get_types_from_idl(part.split("\n", 1)[1]))
    else:
        found.update(get_types_from_idl(text))
    return found


class McapSource(BagSource):
    """MCAP files read by channel: only the ``needed`` topics' schemas and messages.

    ``counts`` are the folder's ``metadata.yaml`` counts by topic (None for a bare file).
    """

    def __init__(
        self,
        name: str,
        files: Sequence[Path],
        needed: Collection[str],
        stack: ExitStack,
        counts: dict[str, int] | None = None,
    ) -> None:
        bare = len(files) == 1 and counts is None
        self._files = []
        for path in files:
            label = name if bare else str(Path(name, path.name))
            if not path.is_file():
                msg = f"{label}: missing (metadata.yaml lists it)"
                raise BagError(msg)
            verify_mcap(path, label)
            self._files.append(_open(path, label, stack))
        self._counts = counts
        topics: dict[str, str] = {}
        kinds: dict[str, set[str]] = {}
        skipped: dict[str, str] = {}
        for one in self._files:
            for topic, channels in one.by_topic.items():
                for channel in channels:
                    schema = one.schemas.get(channel.schema_id)
                    kinds.setdefault(topic, set()).add("" if schema is None else schema.name)
                    if topic not in needed and (why := self._foreign(channel, schema)):
                        skipped[topic] = why
        for topic, names in kinds.items():
            if len(names) == 1 and (msgtype := next(iter(names))):
                topics[topic] = msgtype
        self._store = self._typestore(name, [t for t in needed if t in topics])
        starts = [one.start for one in self._files if one.start is not None]
        super().__init__(
            name,
            topics,
            self._store.fielddefs,
            min(starts) if starts else 0,
            tuple(f"{t} ({w})" for t, w in sorted(skipped.items())),
        )

    @staticmethod
    def _foreign(channel: Channel, schema: Schema | None) -> str | None:
        """Why a channel holds no plain ROS 2 messages (service, foreign encoding), or None."""
        name = "no schema" if schema is None else schema.name
        if channel.message_encoding != "cdr":
            return f"{name}: {channel.message_encoding or 'no'} encoding, not CDR"
        if schema is not None and schema.encoding not in _DEFINITIONS:
            return f"{name}: a {schema.encoding} schema, not a ROS 2 message definition"
        why = not_messages(name)
        return None if why is None else f"{name}: {why}"

    def _typestore(self, name: str, needed: Sequence[str]) -> Typestore:
        """The Humble and swarmtag_msgs types, with the needed channels' own schemas on top."""
        from rosbags.typesys import Stores, get_typestore  # noqa: PLC0415

        found: dict[str, Any] = {}
        for topic in needed:
            for one in self._files:
                for channel in one.by_topic.get(topic, ()):
                    schema = one.schemas.get(channel.schema_id)
                    if channel.message_encoding != "cdr" or (
                        schema is not None and schema.encoding not in _DEFINITIONS
                    ):
                        why = self._foreign(channel, schema)
                        msg = f"{one.label}: topic {topic} holds no ROS 2 messages ({why})"
                        raise BagError(msg)
                    if schema is None or not schema.encoding:
                        continue
                    try:
                        found.update(_types(schema))
                    except Exception as error:  # noqa: BLE001 - rosbags' parser raises many kinds
                        msg = (
                            f"{one.label}: the {schema.encoding} schema of {topic} "
                            f"({schema.name}) cannot be read ({one_line(error)})"
                        )
                        raise BagError(msg) from None
        store = get_typestore(Stores.EMPTY)
        try:
            store.register({**typestore().fielddefs, **found})
        except Exception as error:  # noqa: BLE001
            msg = (
                f"{name}: the schemas of the mapped topics do not fit together ({one_line(error)})"
            )
            raise BagError(msg) from None
        return store

    def raw(self, topic: str) -> Iterator[tuple[int, bytes]]:
        """The messages of ``topic``, file by file; each file's held against its statistics."""
        for one in self._files:
            channels = one.by_topic.get(topic, [])
            count = 0
            if channels:
                for _, _, message in one.reader.iter_messages(topics=[topic], log_time_order=True):
                    count += 1
                    yield message.log_time, message.data
            stated = None if one.counts is None else sum(one.counts.get(c.id, 0) for c in channels)
            if stated is not None and count < stated:
                msg = (
                    f"{one.label}: topic {topic}: read {count} message(s), but the file's "
                    f"statistics count {stated}; the file is damaged, so nothing is imported"
                )
                raise BagError(msg)

    def deserialize(self, raw: bytes, msgtype: str) -> object:
        """``raw`` decoded with the mapped channels' own schemas (or the Humble types)."""
        return self._store.deserialize_cdr(raw, msgtype)

    def stated(self, topic: str) -> list[tuple[str, int]]:
        """The folder's ``metadata.yaml`` count of ``topic`` (the files' are checked in ``raw``)."""
        return [] if self._counts is None else [("metadata.yaml", self._counts.get(topic, 0))]
