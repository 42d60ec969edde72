"""Reading a recorded run for ``swarmtag console --replay FILE``: an event log or an MCAP run.

What a file holds decides what the page can show:

- an event log (``.csv``, ``.parquet``; ``swarmtag simulate --events``), read
  with ``swarmtag.io.read_event_log``: carrier events only (ordered, picked up,
  delivered, by whom), so the page shows the tags and the KPIs over time and
  says that the file holds no robot poses;
- an MCAP run (``swarmtag simulate --mcap``), whose event log is read with
  ``swarmtag.io.bags.read_bag`` (as ``swarmtag log import`` does), and whose
  ``/swarmtag/robots`` and ``/swarmtag/carriers`` poses, ``/swarmtag/tag_status``
  changes, ``/swarmtag/arena`` floor and ``/swarmtag/scene`` body sizes, where
  present, are read with the same MCAP reader (``swarmtag.io.mcap_in.McapSource``),
  so that the floor, the robots and the carriers are drawn too, and every tag
  change (urgency growth, lifts, deliveries) shows when it happened. A rosbag2 folder or ``.db3``
  gives its event log only.

Memory is bounded by refusing files over ``MAX_REPLAY_BYTES`` before
reading them; poses are kept as float32 arrays (16 bytes a robot a frame).
Every refusal is one line naming the file (a ``SwarmtagError``).
"""

from __future__ import annotations

import math
import os
from contextlib import ExitStack
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Final

import numpy as np
from numpy.typing import NDArray

from swarmtag._inputs import check_path
from swarmtag._resources import format_bytes
from swarmtag.errors import BagError, ConfigError, EventLogError
from swarmtag.io import CarrierLog, read_event_log

__all__ = ["MAX_REPLAY_BYTES", "Poses", "Recording", "TagTimeline", "read_recording"]

MAX_REPLAY_BYTES: Final = 64 * 2**20
"""The largest file (or bag folder) a replay reads: 64 MiB, about 600,000 event-log rows or
an MCAP run of some 100,000 ticks of 3 robots; larger files are refused before reading."""
_POSE_TOPICS: Final = ("/swarmtag/trial", "/swarmtag/robots", "/swarmtag/carriers")
_PICTURE_TOPICS: Final = ("/swarmtag/arena", "/swarmtag/scene", "/swarmtag/tag_status")
_PICKED_UP: Final = 2


@dataclass(frozen=True)
class Poses:
    """One run's poses: ``times`` (s from the trial start), robots (x, y, hx, hy), carriers."""

    times: NDArray[np.float64]
    robots: NDArray[np.float32]
    """(frames, robots, 4): position and unit heading."""
    carriers: NDArray[np.float32]
    """(frames, carriers, 2): position, in the order of ``markers``."""
    markers: tuple[int, ...]


@dataclass(frozen=True)
class TagTimeline:
    """One tag's changes in a run (``/swarmtag/tag_status``): when, and what it held from then.

    ``carried_by`` is the robot that lifted it while it is picked up, else -1.
    """

    times: NDArray[np.float64]
    status: NDArray[np.int8]
    urgency: NDArray[np.int8]
    carried_by: NDArray[np.int32]


@dataclass(frozen=True)
class Recording:
    """A file's event log, and what else it held: poses by (condition, run), the floor."""

    name: str
    log: CarrierLog
    tick_seconds: float
    """Seconds per tick, to show a log in ticks in seconds (1 for a log in seconds)."""
    poses: dict[tuple[str, int], Poses] = field(default_factory=dict)
    floor: dict[str, Any] | None = None
    """The floor picture (``kind`` arena or map, as ``SimSource.floor``), or None: no floor."""
    tags: dict[tuple[str, int], dict[int, TagTimeline]] = field(default_factory=dict)
    """Each run's tag changes by marker, where the file has them (an MCAP run)."""


def _size(path: Path) -> int:
    if path.is_dir():
        return sum(p.stat().st_size for p in path.rglob("*") if p.is_file())
    return path.stat().st_size


def read_recording(path: str | os.PathLike[str], *, tick_seconds: float) -> Recording:
    """The recording in ``path``; ``tick_seconds`` scales an event log in ticks.

    Refuses (one line) a missing file, one over ``MAX_REPLAY_BYTES``, a format
    other than ``.csv``, ``.parquet``, ``.mcap``, ``.db3`` or a rosbag2 folder,
    and anything the io readers refuse.
    """
    name = os.fspath(path)
    checked = check_path(path, what="replay file", error=ConfigError)
    if not checked.exists():
        raise ConfigError(f"--replay {name}: no such file")
    size = _size(checked)
    if size > MAX_REPLAY_BYTES:
        raise ConfigError(
            f"--replay {name}: {format_bytes(size)} is over the replay limit of "
            f"{format_bytes(MAX_REPLAY_BYTES)}; replay a shorter run (simulate --runs, --ticks)"
        )
    suffix = checked.suffix.lower()
    if checked.is_dir() or suffix in (".mcap", ".db3"):
        return _read_bag(checked, name)
    if suffix not in (".csv", ".parquet", ".pq"):
        raise ConfigError(
            f"--replay {name}: not an event log (.csv, .parquet) or a run (.mcap, a rosbag2 folder)"
        )
    try:
        log = read_event_log(checked)
    except EventLogError as error:
        raise EventLogError(f"--replay {error}") from None
    if len(log) == 0:
        raise EventLogError(f"--replay {name}: the event log has no rows")
    return Recording(name, log, tick_seconds if log.time_unit == "tick" else 1.0)


def _read_bag(path: Path, name: str) -> Recording:
    """An MCAP run (or another bag): its event log, and its poses and floor where it has them."""
    from swarmtag.io.bags import read_bag  # noqa: PLC0415 - the bags extra

    try:
        log = read_bag(path).carriers
    except BagError as error:
        raise BagError(f"--replay {error}") from None
    if path.is_dir() or path.suffix.lower() != ".mcap":
        return Recording(name, log, 1.0)
    from swarmtag.io.mcap_in import McapSource  # noqa: PLC0415 - the bags extra

    with ExitStack() as stack:
        source = McapSource(name, [path], (*_POSE_TOPICS, *_PICTURE_TOPICS), stack)
        if not all(topic in source.topics for topic in _POSE_TOPICS):
            return Recording(name, log, 1.0)
        starts, tick = _trial_starts(source)
        poses = _poses(source, starts)
        floor = _floor(source)
        tags = _tag_changes(source, starts)
    return Recording(name, log, tick if log.time_unit == "tick" else 1.0, poses, floor, tags)


def _trial_starts(source: Any) -> tuple[list[tuple[int, str, int, tuple[int, ...]]], float]:  # noqa: ANN401
    """Each trial start: (log time ns, condition, run, markers), and the clock's tick (s)."""
    starts = []
    tick = 0.0
    for _index, at, message in source.messages("/swarmtag/trial"):
        if int(message.event) == 0:
            markers = tuple(int(m) for m in message.markers)
            starts.append((at, str(message.condition), int(message.run), markers))
            tick = float(message.tick) or tick
    return starts, tick if tick > 0 else 1.0


def _poses(
    source: Any,  # noqa: ANN401 - McapSource
    starts: list[tuple[int, str, int, tuple[int, ...]]],
) -> dict[tuple[str, int], Poses]:
    """The robot and carrier poses of each trial, by (condition, run)."""
    if not starts:
        return {}
    begins = np.array([s[0] for s in starts], dtype=np.int64)
    frames: dict[int, tuple[list[float], list[NDArray[np.float32]], list[NDArray[np.float32]]]]
    frames = {i: ([], [], []) for i in range(len(starts))}
    carriers: dict[int, NDArray[np.float32]] = {}
    for _index, at, message in source.messages("/swarmtag/carriers"):
        carriers[at] = np.array(
            [(p.position.x, p.position.y) for p in message.poses], dtype=np.float32
        ).reshape(-1, 2)
    for _index, at, message in source.messages("/swarmtag/robots"):
        trial = int(np.searchsorted(begins, at, side="right")) - 1
        if trial < 0 or at not in carriers:
            continue
        robots = np.array(
            [
                (p.position.x, p.position.y, *_heading(p.orientation.z, p.orientation.w))
                for p in message.poses
            ],
            dtype=np.float32,
        ).reshape(-1, 4)
        times, robot_frames, carrier_frames = frames[trial]
        times.append((at - int(begins[trial])) / 1e9)
        robot_frames.append(robots)
        carrier_frames.append(carriers.pop(at))
    found: dict[tuple[str, int], Poses] = {}
    for trial, (times, robot_frames, carrier_frames) in frames.items():
        if not times or len({f.shape for f in robot_frames}) != 1:
            continue
        if len({f.shape for f in carrier_frames}) != 1:
            continue
        _at, condition, run, markers = starts[trial]
        if carrier_frames[0].shape[0] != len(markers):
            continue
        found[condition, run] = Poses(
            np.array(times), np.stack(robot_frames), np.stack(carrier_frames), markers
        )
    return found


def _tag_changes(
    source: Any,  # noqa: ANN401 - McapSource
    starts: list[tuple[int, str, int, tuple[int, ...]]],
) -> dict[tuple[str, int], dict[int, TagTimeline]]:
    """Every tag change of each trial, by marker, in the order they took effect."""
    if "/swarmtag/tag_status" not in source.topics or not starts:
        return {}
    begins = np.array([s[0] for s in starts], dtype=np.int64)
    rows: dict[tuple[int, int], list[tuple[float, int, int, int]]] = {}
    for _index, at, message in source.messages("/swarmtag/tag_status"):
        trial = int(np.searchsorted(begins, at, side="right")) - 1
        if trial < 0:
            continue
        seconds = (at - int(begins[trial])) / 1e9
        for tag in message.tags:
            changes = rows.setdefault((trial, int(tag.marker)), [])
            carried = changes[-1][3] if changes else -1
            if int(tag.status) != _PICKED_UP:
                carried = -1
            elif int(tag.robot) >= 0:
                carried = int(tag.robot)
            changes.append((seconds, int(tag.status), int(tag.urgency), carried))
    found: dict[tuple[str, int], dict[int, TagTimeline]] = {}
    for (trial, marker), held in rows.items():
        table = np.array(held, dtype=np.float64).reshape(-1, 4)
        _at, condition, run, _markers = starts[trial]
        found.setdefault((condition, run), {})[marker] = TagTimeline(
            table[:, 0].copy(),
            table[:, 1].astype(np.int8),
            table[:, 2].astype(np.int8),
            table[:, 3].astype(np.int32),
        )
    return found


def _heading(z: float, w: float) -> tuple[float, float]:
    """The unit heading of a yaw-only quaternion (z, w)."""
    yaw = 2.0 * math.atan2(z, w)
    return math.cos(yaw), math.sin(yaw)


def _floor(source: Any) -> dict[str, Any] | None:  # noqa: ANN401 - McapSource
    """The floor of the file's ``/swarmtag/arena`` and its body sizes, as ``SimSource.floor``."""
    if "/swarmtag/arena" not in source.topics:
        return None
    parts: dict[str, list[tuple[float, float, float, float]]] = {}
    for _index, _at, message in source.messages("/swarmtag/arena"):
        for m in message.markers:
            x, y, sx, sy = m.pose.position.x, m.pose.position.y, m.scale.x, m.scale.y
            parts.setdefault(str(m.ns), []).append((x - sx / 2, y - sy / 2, sx, sy))
        break
    if "floor" not in parts:
        return None
    _x, _y, arena, height = parts["floor"][0]
    robot_radius, carrier_size = _sizes(source)
    picture: dict[str, Any] = {
        "kind": "arena",
        "arena": arena,
        "height": height,
        "pickup_right": 0.0,
        "dropoff_left": arena,
        "robot_radius": robot_radius,
        "carrier_size": carrier_size,
        "floor_text": "",
        "floor_cell": 0.0,
        "destinations": [0],
    }
    if "shelf" in parts or len(parts.get("pickup", ())) > 1:
        picture.update(kind="map", **_map(parts, arena, height))
    else:
        pickup, dropoff = parts.get("pickup", []), parts.get("dropoff", [])
        if pickup:
            picture["pickup_right"] = pickup[0][0] + pickup[0][2]
        if dropoff:
            picture["dropoff_left"] = dropoff[0][0]
    return picture


def _sizes(source: Any) -> tuple[float, float]:  # noqa: ANN401 - McapSource
    """A robot's radius and a carrier's side, from the first scene (0.1 m each without one)."""
    robot_radius, carrier_size = 0.1, 0.1
    if "/swarmtag/scene" in source.topics:
        for _index, _at, message in source.messages("/swarmtag/scene"):
            for m in message.markers:
                if m.ns == "robots":
                    robot_radius = m.scale.x / 2
                elif m.ns == "carriers":
                    carrier_size = m.scale.x
            break
    return robot_radius, carrier_size


def _map(
    parts: dict[str, list[tuple[float, float, float, float]]], arena: float, height: float
) -> dict[str, Any]:
    """A warehouse's cells back as the map text the page draws (drop-off areas shown as 0)."""
    cells = [c for kind in ("shelf", "pickup", "dropoff") for c in parts.get(kind, [])]
    side = min(c[2] for c in cells)
    rows, columns = round(height / side), round(arena / side)
    grid = [["." for _ in range(columns)] for _ in range(rows)]
    for kind, char in (("shelf", "#"), ("pickup", "P"), ("dropoff", "0")):
        for x, y, _sx, _sy in parts.get(kind, []):
            column, row = round(x / side), rows - 1 - round(y / side)
            if 0 <= row < rows and 0 <= column < columns:
                grid[row][column] = char
    return {"floor_text": "\n".join("".join(r) for r in grid), "floor_cell": side}
