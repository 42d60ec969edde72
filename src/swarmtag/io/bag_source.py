"""An open bag as ``swarmtag.io.bags`` reads it: topics, types, and one topic's messages, counted.

Two kinds: ``McapSource`` (``swarmtag.io.mcap_in``: MCAP files, read by channel with
Foxglove's ``mcap``) and ``RosbagsSource`` here (sqlite3 bags and file-compressed folders,
through ``rosbags``' ``AnyReader``). Both read only the topics asked for, and both hold every
topic they read against the message counts the bag states (its ``metadata.yaml``, its MCAP
statistics, its database): a topic read short is one ``BagError`` line naming the topic and
both counts, never a shorter log.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from collections.abc import Iterator
from typing import TYPE_CHECKING, Any, Final

from swarmtag._interrupt import checkpoint
from swarmtag.errors import BagError

if TYPE_CHECKING:
    from rosbags.highlevel import AnyReader

__all__ = ["BagSource", "RosbagsSource", "not_messages"]

_NOT_MESSAGES: Final = {"/srv/": "service events", "/action/": "action events"}


def not_messages(msgtype: str) -> str | None:
    """Why a topic of type ``msgtype`` holds no plain messages (service, action), or None."""
    return next((why for part, why in _NOT_MESSAGES.items() if part in msgtype), None)


class BagSource(ABC):
    """An open bag: its topics and types, where it starts, and what it holds that is not read.

    ``topics``: topic -> its one type; ``fielddefs``: the types' definitions (``rosbags``);
    ``start``: the first log time (ns); ``skipped``: the topics not read that hold no plain
    messages (services, foreign encodings), described.
    """

    def __init__(
        self,
        name: str,
        topics: dict[str, str],
        fielddefs: Any,  # noqa: ANN401 - rosbags' field definitions
        start: int,
        skipped: tuple[str, ...] = (),
    ) -> None:
        self.name, self.topics, self.fielddefs = name, topics, fielddefs
        self.start, self.skipped = start, skipped

    @abstractmethod
    def raw(self, topic: str) -> Iterator[tuple[int, bytes]]:
        """(log time, CDR bytes) of every message on ``topic``, in the bag's order."""

    @abstractmethod
    def deserialize(self, raw: bytes, msgtype: str) -> object:
        """The message ``raw`` of type ``msgtype``."""

    @abstractmethod
    def stated(self, topic: str) -> list[tuple[str, int]]:
        """How many messages the bag says ``topic`` holds: (who says so, count) for each record."""

    def messages(self, topic: str) -> Iterator[tuple[int, int, object]]:
        """(index, log time, message) of every message on ``topic``, then the count check."""
        msgtype = self.topics[topic]
        count = 0
        for at, raw in self.raw(topic):
            checkpoint()  # a Ctrl-C that the storage library swallowed ends the reading here
            yield count, at, self.deserialize(raw, msgtype)
            count += 1
        for who, stated in self.stated(topic):
            if count < stated:
                msg = (
                    f"{self.name}: topic {topic}: read {count} message(s), but {who} counts "
                    f"{stated}; the bag is damaged or its records disagree, so nothing is imported"
                )
                raise BagError(msg)


class RosbagsSource(BagSource):
    """A bag read through ``rosbags``' ``AnyReader`` (open): sqlite3 storage, compressed folders.

    The counts held against are the reader's per-topic counts: ``metadata.yaml``'s for a
    folder, the database's own for a bare ``.db3`` file.
    """

    def __init__(self, name: str, reader: AnyReader, *, folder: bool) -> None:
        self.reader = reader
        infos = reader.topics
        topics = {t: info.msgtype for t, info in infos.items() if info.msgtype}
        skipped = tuple(
            f"{topic} ({msgtype}: {why})"
            for topic, msgtype in sorted(topics.items())
            if (why := not_messages(msgtype))
        )
        start = reader.start_time if reader.message_count else 0
        super().__init__(name, topics, reader.typestore.fielddefs, start, skipped)
        self._who = "metadata.yaml" if folder else "the bag's database"

    def raw(self, topic: str) -> Iterator[tuple[int, bytes]]:
        """The messages of the connections of ``topic``, in log-time order."""
        connections = [c for c in self.reader.connections if c.topic == topic]
        for _, at, data in self.reader.messages(connections=connections):
            yield at, data

    def deserialize(self, raw: bytes, msgtype: str) -> object:
        """``raw`` decoded with the bag's own types (or the Humble ones it lacks)."""
        return self.reader.deserialize(raw, msgtype)

    def stated(self, topic: str) -> list[tuple[str, int]]:
        """The reader's count of ``topic``: metadata.yaml's, or the database's."""
        info = self.reader.topics.get(topic)
        return [] if info is None else [(self._who, int(info.msgcount))]
