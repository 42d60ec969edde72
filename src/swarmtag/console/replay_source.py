"""The console's ``--replay`` source: a recorded run played back, with play/pause, seek, speed.

A ``Recording`` (``swarmtag.console.replay_file``) holds an event log, one
row per carrier per run, and maybe the runs' poses. The replay lays its
runs end to end on one time line, condition by condition and run by run
(each as long as its ``run_end``, or its last event), and shows the moment
the play head is at: which carriers were ordered by then, which were picked
up and by which robot, which were delivered. An MCAP run records every tag
change (``/swarmtag/tag_status``: each lift, delivery and urgency change),
and the table shows exactly those; an event log records only the order,
the last pickup and the delivery, so there a carrier's urgency is the one it
was ordered with until its delivery, then the one it was delivered with.
Robots and carrier positions come from the poses where the file had them. The KPIs are those of the
runs of the shown condition up to the play head: earlier runs whole, the
current one cut at the play head (orders, pickups and deliveries after it
not yet happened).

A replay takes no writes: ``swarmtag.console.writes.ReadOnlyDesk`` refuses
them with ``REPLAY_REFUSAL``. Every public method holds the source's lock.
"""

from __future__ import annotations

import math
import threading
from dataclasses import dataclass
from typing import Any, Final

import numpy as np
from numpy.typing import NDArray

from swarmtag.console.kpis import log_kpis
from swarmtag.console.replay_file import Poses, Recording, TagTimeline
from swarmtag.errors import ConfigError
from swarmtag.io import MISSING_ID, CarrierLog
from swarmtag.tag import TagState, TagStatus

__all__ = ["MAX_SPEED", "MIN_SPEED", "REPLAY_REFUSAL", "ReplaySource"]

REPLAY_REFUSAL: Final = (
    "a replay cannot be re-prioritised: it shows a recorded run; "
    "use --sim or --scan to write to tags"
)
MIN_SPEED: Final = 0.01
MAX_SPEED: Final = 100.0
_NO_POSES: Final = "this file holds carrier events only: no robot poses, so no floor is drawn"


@dataclass(frozen=True)
class _Segment:
    """One run on the time line: its rows of the log, where it starts, how long it lasts (s)."""

    condition: str
    run: int
    rows: NDArray[np.int64]
    start: float
    duration: float
    poses: Poses | None
    tags: dict[int, TagTimeline]


def _seconds(values: NDArray[np.float64], scale: float) -> NDArray[np.float64]:
    return np.asarray(values, dtype=np.float64) * scale


class ReplaySource:
    """A recording played back ``speed`` times real time; ``control`` plays, pauses, seeks."""

    kind = "replay"

    def __init__(self, recording: Recording, *, speed: float = 1.0) -> None:
        self.recording = recording
        self.speed = speed
        self._lock = threading.RLock()
        log = recording.log
        self._scale = recording.tick_seconds
        self._segments: list[_Segment] = []
        start = 0.0
        for condition in log.conditions:
            ofcondition = np.flatnonzero(log.condition == condition)
            ordered = ofcondition[np.argsort(log.run[ofcondition], kind="stable")]
            runs, firsts = np.unique(log.run[ordered], return_index=True)
            for run, rows in zip(runs.tolist(), np.split(ordered, firsts[1:]), strict=True):
                poses = recording.poses.get((condition, int(run)))
                duration = self._duration(rows, poses)
                tags = recording.tags.get((condition, int(run)), {})
                self._segments.append(
                    _Segment(condition, int(run), rows, start, duration, poses, tags)
                )
                start += duration
        self.duration = start
        self._starts = np.array([s.start for s in self._segments])
        self._markers = frozenset(int(m) for m in np.unique(log.carrier) if m < 256)
        self._time = 0.0
        self._playing = True
        self._version = 0
        """How many controls were applied: a page drops state older than its last control."""

    def _duration(self, rows: NDArray[np.int64], poses: Poses | None) -> float:
        """A run's length in seconds: its ``run_end``, else its last event (at least 1 s)."""
        log = self.recording.log
        times = [log.run_end[rows], log.delivery_time[rows], log.pickup_time[rows]]
        times.append(log.order_time[rows])
        finite = np.concatenate([t[np.isfinite(t)] for t in times])
        end = float(finite.max()) * self._scale if finite.size else 0.0
        if poses is not None and poses.times.size:
            end = max(end, float(poses.times[-1]))
        return max(end, 1.0)

    @property
    def markers(self) -> frozenset[int]:
        """Every carrier of the file (writes to them are refused, as all writes here)."""
        return self._markers

    def start(self) -> None:
        """Nothing to switch on."""

    def stop(self) -> None:
        """Nothing to release."""

    def advance(self, seconds: float) -> int:
        """Move the play head ``seconds * speed`` on while playing; it stops at the end."""
        with self._lock:
            if not self._playing:
                return 0
            self._time = min(self.duration, self._time + seconds * self.speed)
            if self._time >= self.duration:
                self._playing = False
            return 1

    def control(self, data: object) -> dict[str, Any]:
        """Apply ``{"playing": bool, "time": s, "speed": x}`` (any of them); the new status.

        ``ConfigError`` names the first bad key or value; nothing changes then.
        """
        if not isinstance(data, dict) or not data:
            raise ConfigError('send an object with any of "playing", "time", "speed"')
        unknown = sorted(set(data) - {"playing", "time", "speed"})
        if unknown:
            raise ConfigError(f"unknown key {unknown[0][:20]!r}: send playing, time or speed")
        playing, time, speed = data.get("playing"), data.get("time"), data.get("speed")
        if playing is not None and not isinstance(playing, bool):
            raise ConfigError("playing: give true or false")
        for name, value, low, high in (
            ("time", time, 0.0, self.duration),
            ("speed", speed, MIN_SPEED, MAX_SPEED),
        ):
            if value is None:
                continue
            if isinstance(value, bool) or not isinstance(value, int | float):
                raise ConfigError(f"{name}: give a number")
            if not (math.isfinite(value) and low <= value <= high):
                raise ConfigError(f"{name}: {value!r} is not in {low:g}-{high:g}")
        with self._lock:
            if time is not None:
                self._time = float(time)
            if speed is not None:
                self.speed = float(speed)
            if playing is not None:
                self._playing = playing and self._time < self.duration
            self._version += 1
            return self._status()

    def _status(self) -> dict[str, Any]:
        segment = self._segment()
        return {
            "version": self._version,
            "playing": self._playing,
            "position": round(self._time, 3),
            "duration": round(self.duration, 3),
            "speed": self.speed,
            "segment": self._segments.index(segment),
            "segments": len(self._segments),
            "condition": segment.condition,
            "starts": [round(s.start, 3) for s in self._segments],
        }

    def _segment(self) -> _Segment:
        index = int(np.searchsorted(self._starts, self._time, side="right")) - 1
        return self._segments[max(0, min(index, len(self._segments) - 1))]

    def floor(self) -> dict[str, Any]:
        """The file's floor, or ``kind: none`` and why (an event log has no poses)."""
        if self.recording.floor is not None and self.recording.poses:
            return {**self.recording.floor, "tick_seconds": self._scale, "file": self._name()}
        return {"kind": "none", "why": _NO_POSES, "destinations": [0], "file": self._name()}

    def _name(self) -> str:
        return self.recording.name.rsplit("/", 1)[-1]

    def _rows(self, segment: _Segment, local: float) -> list[dict[str, Any]]:
        """The carriers of ``segment`` ordered by ``local`` seconds, as the tag table's rows."""
        log, rows, scale = self.recording.log, segment.rows, self._scale
        order = _seconds(log.order_time[rows], scale)
        pickup = _seconds(log.pickup_time[rows], scale)
        delivery = _seconds(log.delivery_time[rows], scale)
        poses, frame = segment.poses, 0
        if poses is not None:
            frame = max(0, int(np.searchsorted(poses.times, local, side="right")) - 1)
        found = []
        for i, row in enumerate(rows.tolist()):
            if order[i] > local:
                continue
            marker = int(log.carrier[row])
            delivered = bool(delivery[i] <= local)
            lifted = bool(pickup[i] <= local) and not delivered
            urgency = int(log.urgency0[row])
            if delivered and int(log.urgency_end[row]) != MISSING_ID:
                urgency = int(log.urgency_end[row])
            robot = int(log.robot[row])
            carried = robot if lifted and robot != MISSING_ID else None
            status = "idle" if delivered else "picked_up" if lifted else "awaiting_pickup"
            timeline = segment.tags.get(marker)
            if timeline is not None:  # the file's own tag changes
                at = int(np.searchsorted(timeline.times, local, side="right")) - 1
                if at >= 0:
                    urgency = int(timeline.urgency[at])
                    status = TagStatus(int(timeline.status[at])).name.lower()
                    carried = int(timeline.carried_by[at]) if timeline.carried_by[at] >= 0 else None
            x = y = None
            if poses is not None and marker in poses.markers:
                where = poses.carriers[frame, poses.markers.index(marker)]
                x, y = round(float(where[0]), 3), round(float(where[1]), 3)
            found.append(
                {
                    "marker": marker,
                    "urgency": urgency,
                    "status": status,
                    "destination": 0,
                    "last_heard": None,
                    "carried_by": carried,
                    "x": x,
                    "y": y,
                    "present": x is not None and not delivered,
                    "order_time": round(float(order[i]), 3),
                    "delivered_at": round(float(delivery[i]), 3) if delivered else None,
                }
            )
        return found

    def snapshot(self) -> dict[str, Any]:
        """The moment at the play head: its run, time in the run, robots and tags."""
        with self._lock:
            segment = self._segment()
            local = self._time - segment.start
            robots = []
            if segment.poses is not None:
                poses = segment.poses
                frame = max(0, int(np.searchsorted(poses.times, local, side="right")) - 1)
                robots = [
                    {
                        "id": n,
                        "x": round(float(x), 3),
                        "y": round(float(y), 3),
                        "hx": round(float(hx), 3),
                        "hy": round(float(hy), 3),
                        "mode": None,
                        "target": None,
                    }
                    for n, (x, y, hx, hy) in enumerate(poses.robots[frame].tolist())
                ]
            return {
                "run": segment.run,
                "tick": round(local / self._scale) if self._scale != 1.0 else None,
                "time": round(local, 3),
                "robots": robots,
                "tags": self._rows(segment, local),
                "replay": self._status(),
            }

    def tag_state(self, marker: int) -> TagState:
        """The tag of ``marker`` at the play head (``KeyError``: not ordered yet in this run)."""
        with self._lock:
            segment = self._segment()
            for row in self._rows(segment, self._time - segment.start):
                if row["marker"] == marker:
                    return TagState(
                        urgency=row["urgency"],
                        status=TagStatus.parse(row["status"]),
                        destination=0,
                        marker=marker,
                    )
            raise KeyError(marker)

    def kpis(self) -> dict[str, Any]:
        """The KPIs of the shown condition's runs up to the play head (the current one cut)."""
        with self._lock:
            segment = self._segment()
            cut = round((self._time - segment.start) / self._scale, 6)
            earlier = [
                s.rows
                for s in self._segments
                if s.condition == segment.condition and s.start < segment.start
            ]
            log = self.recording.log
            parts = [log.take(np.concatenate(earlier))] if earlier else []
            parts.append(_cut(log.take(segment.rows), cut))
            answer = log_kpis(CarrierLog.concat(parts), segment.condition, self._scale)
            return {**answer, "runs": len(earlier) + 1}


def _cut(log: CarrierLog, cut: float) -> CarrierLog:
    """One run's rows as they stood at ``cut`` (the log's unit): later events not yet happened."""
    keep = np.flatnonzero(log.order_time <= cut)
    part = log.take(keep)
    picked = part.pickup_time <= cut
    delivered = part.delivery_time <= cut
    return CarrierLog(
        condition=part.condition,
        run=part.run,
        seed=part.seed,
        carrier=part.carrier,
        urgency0=part.urgency0,
        order_time=part.order_time,
        pickup_time=np.where(picked, part.pickup_time, np.nan),
        delivery_time=np.where(delivered, part.delivery_time, np.nan),
        robot=np.where(delivered, part.robot, MISSING_ID),
        time_unit=part.time_unit,
        run_end=np.full(len(part), cut),
        urgency_end=np.where(delivered, part.urgency_end, MISSING_ID),
    )
