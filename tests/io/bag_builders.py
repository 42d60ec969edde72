"""Bags built in the tests with rosbags' own writer: a two-trial lab session and its event log.

``write_bag`` writes messages into a rosbag2 folder (sqlite3 or MCAP storage) or a bare
``.mcap``/``.db3`` file. ``lab_session`` is a physical-style session in the swarmtag_msgs
layout whose event log is written out by hand in ``LAB_LOG`` (and its event table in
``LAB_TABLE``): the exact answer ``swarmtag log import`` must give.
"""

from __future__ import annotations

import math
import shutil
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from swarmtag.io import CarrierLog, EventTable
from swarmtag.io.ros_types import typestore

NAN = math.nan
T0 = 1_700_000_000 * 10**9
"""Trial A's start: a wall-clock stamp, as a robot system records it (ns since 1970)."""
LATENCY = 3_000_000
"""The bag records each message 3 ms after its header stamp (the import must use the stamp)."""
SEC = 10**9

Message = tuple[str, int, Any]
"""topic, log time (ns), message object."""


def write_bag(
    path: Path,
    storage: str,
    topics: dict[str, str],
    messages: Sequence[Message],
    store: Any = None,
) -> Path:
    """Write ``messages`` (topic -> type in ``topics``) as a bag; the path to give the reader.

    ``storage``: ``sqlite3`` or ``mcap`` (a rosbag2 folder), ``db3`` or ``bare-mcap`` (the
    storage file alone, moved out of its folder).
    """
    from rosbags.rosbag2 import StoragePlugin, Writer

    store = store or typestore()
    plugin = StoragePlugin.SQLITE3 if storage in ("sqlite3", "db3") else StoragePlugin.MCAP
    folder = path if storage in ("sqlite3", "mcap") else path.with_name(path.name + ".folder")
    with Writer(folder, version=9, storage_plugin=plugin) as writer:
        connections = {
            topic: writer.add_connection(topic, msgtype, typestore=store)
            for topic, msgtype in topics.items()
        }
        for topic, at, message in messages:
            data = store.serialize_cdr(message, topics[topic])
            writer.write(connections[topic], at, data)
    if storage in ("sqlite3", "mcap"):
        return folder
    suffix = ".db3" if storage == "db3" else ".mcap"
    (folder / f"{folder.name}{suffix}").replace(path)
    shutil.rmtree(folder)
    return path


class Messages:
    """Builders of swarmtag_msgs messages stamped at ``at`` (ns)."""

    def __init__(self, store: Any = None) -> None:
        self.store = store or typestore()
        self.types = self.store.types

    def header(self, at: int) -> Any:
        time = self.types["builtin_interfaces/msg/Time"](sec=at // SEC, nanosec=at % SEC)
        return self.types["std_msgs/msg/Header"](stamp=time, frame_id="")

    def trial(
        self,
        at: int,
        *,
        end: bool = False,
        condition: str = "",
        run: int = 0,
        seed: int = 0,
        time_unit: str = "s",
        tick: float = 0.0,
        markers: Sequence[int] = (),
        urgency0: Sequence[int] = (),
        order_time: Sequence[float] = (),
    ) -> Message:
        message = self.types["swarmtag_msgs/msg/Trial"](
            header=self.header(at),
            event=1 if end else 0,
            condition=condition,
            run=run,
            seed=seed,
            time_unit=time_unit,
            tick=tick,
            markers=np.array(markers, dtype=np.uint8),
            urgency0=np.array(urgency0, dtype=np.uint8),
            order_time=np.array(order_time, dtype=np.float64),
        )
        return ("/swarmtag/trial", at + LATENCY, message)

    def tags(self, at: int, *changes: tuple[int, int, int, int]) -> Message:
        """Tag changes (marker, status, urgency, robot) at ``at``."""
        entry = self.types["swarmtag_msgs/msg/TagStatus"]
        tags = [
            entry(marker=m, urgency=u, status=s, destination=0, robot=r) for m, s, u, r in changes
        ]
        message = self.types["swarmtag_msgs/msg/TagStatusArray"](header=self.header(at), tags=tags)
        return ("/swarmtag/tag_status", at + LATENCY, message)

    def events(self, at: int, *events: tuple[str, int, int, float]) -> Message:
        """Robot events (kind, robot, carrier, value) at ``at``."""
        entry = self.types["swarmtag_msgs/msg/RobotEvent"]
        rows = [entry(kind=k, robot=r, carrier=c, value=v) for k, r, c, v in events]
        message = self.types["swarmtag_msgs/msg/RobotEventArray"](
            header=self.header(at), events=rows
        )
        return ("/swarmtag/robot_events", at + LATENCY, message)


TOPICS = {
    "/swarmtag/trial": "swarmtag_msgs/msg/Trial",
    "/swarmtag/tag_status": "swarmtag_msgs/msg/TagStatusArray",
    "/swarmtag/robot_events": "swarmtag_msgs/msg/RobotEventArray",
}
IDLE, AWAITING, PICKED_UP = 0, 1, 2
B0 = T0 + 100 * SEC
"""Trial B's start."""


def lab_session(build: Messages | None = None) -> list[Message]:
    """Two trials in one bag, in the default layout (see ``LAB_LOG`` for what they give).

    Trial A (proximity, run 0): no carrier list, so its carriers come from the tag states;
    carrier 3 is lifted, returned by an operator after a breakdown, lifted again and
    delivered; carrier 8 waits at the start and is delivered; carrier 12 is ordered during
    the trial and never lifted. Trial B (urgency:alpha=0.7, run 1) lists its carriers, has
    no end message, and carrier 20's changes (not listed) are ignored.
    """
    m = build or Messages()
    s = SEC
    return sorted(
        [
            m.events(T0 - 5 * s, ("select", 0, 3, 5.0)),  # before any trial: dropped
            m.tags(T0 - 40 * s, (3, AWAITING, 5, -1)),
            m.tags(T0 - 10 * s, (8, AWAITING, 9, -1), (12, IDLE, 2, -1)),
            m.trial(T0, condition="proximity", run=0, seed=7),
            m.events(T0 + 2 * s, ("select", 1, 8, 9.0), ("candidates", 1, 8, 2.0)),
            m.tags(T0 + 5 * s, (12, AWAITING, 2, -1)),
            m.tags(T0 + 12_500_000_000, (8, PICKED_UP, 9, 1)),
            m.events(T0 + 12_500_000_000, ("lift", 1, 8, 9.0)),
            m.tags(T0 + 13 * s, (8, PICKED_UP, 9, -1)),  # repeated state: no change
            m.tags(T0 + 20 * s, (3, AWAITING, 7, -1)),  # re-prioritised by the WMS
            m.tags(T0 + 30_250_000_000, (8, IDLE, 9, 1)),
            m.tags(T0 + 40 * s, (3, PICKED_UP, 7, 0)),
            m.events(T0 + 45 * s, ("breakdown", 0, 3, NAN)),
            m.tags(T0 + 50 * s, (3, AWAITING, 7, -1)),  # an operator returns it: no delivery
            m.tags(T0 + 55 * s, (3, PICKED_UP, 7, 2)),
            m.tags(T0 + 70 * s, (3, IDLE, 7, 2)),
            m.trial(T0 + 90 * s, end=True),
            m.tags(T0 + 99 * s, (3, AWAITING, 4, -1)),
            m.tags(T0 + 99_500_000_000, (8, AWAITING, 6, -1)),
            m.trial(
                B0,
                condition="urgency:alpha=0.7",
                run=1,
                seed=7,
                markers=[3, 8],
                urgency0=[4, 6],
                order_time=[-30.0, -5.5],
            ),
            m.tags(B0 + 2 * s, (20, AWAITING, 9, -1)),
            m.tags(B0 + 10 * s, (3, PICKED_UP, 4, 0), (20, PICKED_UP, 9, 1)),
            m.events(B0 + 10 * s, ("lift", 0, 3, 4.0)),
            m.tags(B0 + 25_500_000_000, (3, IDLE, 4, 0)),
            m.tags(B0 + 30 * s, (8, PICKED_UP, 6, 1)),
            m.tags(B0 + 50 * s, (20, IDLE, 9, 1)),
        ],
        key=lambda message: message[1],
    )


LAB_LOG = CarrierLog(
    condition=["proximity"] * 3 + ["urgency:alpha=0.7"] * 2,
    run=[0, 0, 0, 1, 1],
    seed=[7] * 5,
    carrier=[3, 8, 12, 3, 8],
    urgency0=[5, 9, 2, 4, 6],
    order_time=[-40.0, -10.0, 5.0, -30.0, -5.5],
    pickup_time=[55.0, 12.5, NAN, 10.0, 30.0],
    delivery_time=[70.0, 30.25, NAN, 25.5, NAN],
    robot=[2, 1, -1, 0, -1],
    run_end=[90.0, 90.0, 90.0, NAN, NAN],
    urgency_end=[7, 9, 2, 4, 6],
    time_unit="s",
)
"""The event log ``lab_session`` encodes, written out by hand."""
LAB_TABLE = EventTable(
    condition=["proximity"] * 4 + ["urgency:alpha=0.7"],
    seed=[7] * 5,
    run=[0, 0, 0, 0, 1],
    time=[2.0, 2.0, 12.5, 45.0, 10.0],
    kind=["select", "candidates", "lift", "breakdown", "lift"],
    carrier=[8, 8, 8, 3, 3],
    robot=[1, 1, 1, 0, 0],
    value=[9.0, 2.0, 9.0, NAN, 4.0],
    time_unit="s",
)
"""The event table ``lab_session`` encodes."""


def write_fuzz_bags(folder: Path) -> None:
    """The CLI fuzzer's bag inputs: the lab session as a bare MCAP file, a bare .db3 file and
    a rosbag2 folder (``trial.mcap``, ``trial.db3``, ``bag``), and the default mapping.
    """
    from swarmtag.io.bag_mapping import default_mapping

    session = lab_session()
    write_bag(folder / "trial.mcap", "bare-mcap", TOPICS, session)
    write_bag(folder / "trial.db3", "db3", TOPICS, session)
    write_bag(folder / "bag", "sqlite3", TOPICS, session)
    (folder / "mapping.toml").write_text(default_mapping().read_text(encoding="utf-8"))


SERVICE_TOPIC = "/add_two_ints/_service_event"
SERVICE_TYPE = "example_interfaces/srv/AddTwoInts_Event"
SERVICE_SCHEMA = "int64 a\n---\nint64 sum\n"
"""A service-event channel as ``ros2 bag record --all`` writes one (its schema is the .srv text)."""


def write_mcap_file(
    path: Path,
    topics: dict[str, str],
    messages: Sequence[Message],
    *,
    with_service: bool = True,
    store: Any = None,
) -> Path:
    """``messages`` as one MCAP file written with Foxglove's writer (every CRC), with a
    service-event channel (``SERVICE_TOPIC``, two events) among the message channels.
    """
    from mcap.writer import Writer

    store = store or typestore()
    with path.open("wb") as handle:
        writer = Writer(handle, enable_data_crcs=True)
        writer.start(profile="ros2", library="tests")
        channels = {}
        for topic, msgtype in topics.items():
            text, _ = store.generate_msgdef(msgtype, ros_version=2)
            schema = writer.register_schema(msgtype, "ros2msg", text.encode())
            channels[topic] = writer.register_channel(topic, "cdr", schema)
        if with_service:
            schema = writer.register_schema(SERVICE_TYPE, "ros2msg", SERVICE_SCHEMA.encode())
            service = writer.register_channel(SERVICE_TOPIC, "cdr", schema)
            for at in (T0 + SEC, T0 + 2 * SEC):
                writer.add_message(
                    service, log_time=at, data=b"\x00\x01\x00\x00" + bytes(8), publish_time=at
                )
        for topic, at, message in messages:
            data = bytes(store.serialize_cdr(message, topics[topic]))
            writer.add_message(channels[topic], log_time=at, data=data, publish_time=at)
        writer.finish()
    return path
