"""From a bag's trial marks, tag changes and robot events to the event logs of SPEC §8.1 (pure).

``swarmtag.io.bags`` reads the records out of a bag; this module turns them into a
``CarrierLog`` (one row per carrier per trial) and an ``EventTable``. The rules, written down
in docs/trial-logs.md:

- A trial runs from its start mark to its end mark (``run_end``), or, without one, up to the
  next start (``run_end`` empty). Times are relative to the start: seconds, or ticks of a
  simulated clock (``trial_time``).
- A tag change at or before the start is the carrier's state at the start. The trial's
  carriers are those its start mark lists (with urgency and order time), else those
  ``AWAITING_PICKUP`` at the start or becoming it (or ``PICKED_UP``) during the trial.
- Without a list: the order time is when the tag last became ``AWAITING_PICKUP`` at or before
  the start, or first did during the trial; ``urgency0`` is its urgency then.
- The pickup is the carrier's last change to ``PICKED_UP`` before its delivery (or, never
  delivered, before the trial's end); the delivery is its first change from ``PICKED_UP``
  to ``IDLE`` written by a robot (a robot id >= 0), who is ``robot``; a change to ``IDLE``
  written by an operator returns a carrier and is no delivery. ``urgency_end`` is the
  urgency the delivering change carries, or the carrier's last urgency in the trial.

Changes of one carrier at one instant keep the bag's order.

>>> trial_time(2_500_000_000, "s", 0.0), trial_time(2_500_000_000, "tick", 0.1)
(2.5, 25.0)
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Final

import numpy as np
from numpy.typing import NDArray

from swarmtag.errors import BagError, EventLogError
from swarmtag.io.schema import MISSING_ID, TIME_UNITS
from swarmtag.io.tables import CarrierLog, EventTable
from swarmtag.tag import TagStatus

__all__ = [
    "END_OF_TIME",
    "RobotEvents",
    "TagChanges",
    "Trial",
    "TrialMark",
    "carrier_log",
    "event_table",
    "tick_nanoseconds",
    "trial_time",
    "trials",
]

END_OF_TIME: Final = 2**63 - 1
"""The last nanosecond a bag can hold: the end of a trial nothing closes."""
_AWAITING: Final = int(TagStatus.AWAITING_PICKUP)
_PICKED_UP: Final = int(TagStatus.PICKED_UP)
_IDLE: Final = int(TagStatus.IDLE)


def tick_nanoseconds(tick: float) -> int:
    """A simulated clock's tick in whole nanoseconds: stamps are ``start + n * this``."""
    return round(tick * 1e9)


def trial_time(offset: int, time_unit: str, tick: float) -> float:
    """An event-log time from ``offset`` nanoseconds after the trial start.

    With a simulated clock (``tick`` > 0 seconds) an offset of ``n`` whole ticks is ``n``
    ticks, or ``n * tick`` seconds: exactly the simulator's own times. Without one, seconds.
    """
    if tick > 0:
        ticks = offset / tick_nanoseconds(tick)
        return ticks if time_unit == "tick" else ticks * tick
    return offset / 1e9


def _seconds(offset: int) -> str:
    return f"{offset / 1e9:.3f} s"


@dataclass(frozen=True, slots=True)
class TrialMark:
    """A trial start (``starts``) or end message at ``time`` (ns), described by ``where``.

    ``markers``, ``urgency0`` and ``order_time`` list the trial's carriers, or are None.
    """

    time: int
    starts: bool
    where: str
    condition: str = ""
    run: int = 0
    seed: int = 0
    time_unit: str = "s"
    tick: float = 0.0
    markers: tuple[int, ...] | None = None
    urgency0: tuple[int, ...] | None = None
    order_time: tuple[float, ...] | None = None

    def check(self, source: str) -> None:
        """Refuse values no event log can hold, naming ``source`` and ``where``."""

        def fail(problem: str) -> None:
            msg = f"{source}: {self.where}: {problem}"
            raise BagError(msg)

        if self.time_unit not in TIME_UNITS:
            fail(f"time_unit {self.time_unit!r} is not 's' or 'tick'")
        if not (math.isfinite(self.tick) and self.tick >= 0):
            fail(f"tick {self.tick!r} is not a number of seconds >= 0")
        if self.time_unit == "tick" and (self.tick <= 0 or tick_nanoseconds(self.tick) < 1):
            fail(f"times are in ticks but tick is {self.tick!r}; a simulated clock states its tick")
        if self.run < 0 or self.seed < 0:
            fail(f"run {self.run} and seed {self.seed} must be integers >= 0")
        if self.markers is not None:
            lengths = {len(self.markers), len(self.urgency0 or ()), len(self.order_time or ())}
            if len(lengths) > 1:
                fail("markers, urgency0 and order_time have different lengths")
            if len(set(self.markers)) < len(self.markers):
                fail("markers lists a carrier twice")


@dataclass(frozen=True, eq=False)
class TagChanges:
    """Tag changes, bag order: time (ns), marker, ``TagStatus`` value, urgency, robot (-1: none)."""

    time: NDArray[np.int64]
    marker: NDArray[np.int64]
    status: NDArray[np.int64]
    urgency: NDArray[np.int64]
    robot: NDArray[np.int64]


@dataclass(frozen=True, eq=False)
class RobotEvents:
    """Robot events in bag order: time (ns), kind, robot and carrier (-1 none), value (NaN none)."""

    time: NDArray[np.int64]
    kind: list[str]
    robot: NDArray[np.int64]
    carrier: NDArray[np.int64]
    value: NDArray[np.float64]


@dataclass(frozen=True, slots=True)
class Trial:
    """One trial: its start mark, the last nanosecond it covers, and its end (ns) if marked."""

    mark: TrialMark
    until: int
    end: int | None

    @property
    def start(self) -> int:
        """The start time (ns): time 0 of the trial's event log."""
        return self.mark.time

    def time(self, at: int) -> float:
        """The event-log time of nanosecond ``at``."""
        return trial_time(at - self.start, self.mark.time_unit, self.mark.tick)

    def name(self, bag_start: int) -> str:
        """``the trial starting 1.250 s into the bag (run 3 of proximity)``, for messages."""
        return (
            f"the trial starting {_seconds(self.start - bag_start)} into the bag "
            f"(run {self.mark.run} of {self.mark.condition})"
        )


def trials(marks: Sequence[TrialMark], *, source: str) -> list[Trial]:
    """The trials the start and end marks delimit (marks in bag order; sorted by time here)."""
    ordered = sorted(marks, key=lambda mark: mark.time)  # stable: ties keep the bag's order
    found: list[Trial] = []
    open_mark: TrialMark | None = None
    for mark in ordered:
        if mark.starts:
            mark.check(source)
            if open_mark is not None:
                found.append(Trial(open_mark, mark.time - 1, None))
            open_mark = mark
        elif open_mark is None:
            msg = f"{source}: {mark.where} ends a trial, but none was started before it"
            raise BagError(msg)
        else:
            found.append(Trial(open_mark, mark.time, mark.time))
            open_mark = None
    if open_mark is not None:
        found.append(Trial(open_mark, END_OF_TIME, None))
    if not found:
        msg = f"{source}: no trial starts in the bag; nothing to import"
        raise BagError(msg)
    return found


@dataclass(slots=True)
class _Walk:
    """What one carrier did up to a trial's end (times in ns)."""

    status: int | None = None
    urgency: int | None = None
    waiting_at_start: bool = False
    start_urgency: int | None = None
    order_at: int | None = None
    order_urgency: int | None = None
    active: bool = False
    lifts: list[int] = field(default_factory=list)
    delivered_at: int | None = None
    delivered_by: int = MISSING_ID
    delivery_urgency: int | None = None


def _walk(changes: TagChanges, rows: NDArray[np.intp], trial: Trial) -> _Walk:
    """Follow one carrier's changes (``rows``, sorted by time) up to the end of ``trial``."""
    walk = _Walk()
    times = changes.time[rows]
    before = int(np.searchsorted(times, trial.start, side="right"))
    stop = int(np.searchsorted(times, trial.until, side="right"))
    for position in range(stop):
        row = int(rows[position])
        status, urgency = int(changes.status[row]), int(changes.urgency[row])
        at = int(changes.time[row])
        became = status != walk.status
        if status == _AWAITING and became and (position < before or walk.order_at is None):
            walk.order_at, walk.order_urgency = at, urgency
        if position >= before:
            walk.active |= status in (_AWAITING, _PICKED_UP)
            if status == _PICKED_UP and became:
                walk.lifts.append(at)
            if status == _IDLE and walk.status == _PICKED_UP and changes.robot[row] >= 0:
                walk.delivered_at, walk.delivered_by = at, int(changes.robot[row])
                walk.delivery_urgency = urgency
                return walk
        walk.status, walk.urgency = status, urgency
        if position == before - 1:
            walk.waiting_at_start = status == _AWAITING
            walk.start_urgency = urgency
            walk.active = walk.waiting_at_start
            if not walk.waiting_at_start:
                walk.order_at = None
    return walk


def _by_marker(changes: TagChanges) -> dict[int, NDArray[np.intp]]:
    """Row indices of each marker's changes, sorted by time (ties in bag order)."""
    order = np.lexsort((np.arange(len(changes.time)), changes.time, changes.marker))
    markers = changes.marker[order]
    cuts = np.flatnonzero(np.diff(markers)) + 1
    return {
        int(group[0]): rows
        for group, rows in zip(np.split(markers, cuts), np.split(order, cuts), strict=True)
        if group.size
    }


def _trial_rows(
    trial: Trial, changes: TagChanges, groups: dict[int, NDArray[np.intp]], fail: str
) -> list[tuple[int, int, float, float, float, int, int]]:
    """(carrier, urgency0, order, pickup, delivery, robot, urgency_end) for each carrier."""
    empty = np.zeros(0, dtype=np.intp)
    mark = trial.mark
    if mark.markers is not None:
        listed = zip(mark.markers, mark.urgency0 or (), mark.order_time or (), strict=True)
        walks = [(m, _walk(changes, groups.get(m, empty), trial), u, t) for m, u, t in listed]
    else:
        walks = []
        for marker in sorted(groups):
            walk = _walk(changes, groups[marker], trial)
            if not walk.active:
                continue
            if walk.order_at is None:
                msg = (
                    f"{fail}: carrier {marker} is lifted without an order (its tag never was "
                    "awaiting_pickup before); list the trial's carriers in the trial message "
                    "(markers, urgency0, order_time)"
                )
                raise BagError(msg)
            urgency0 = walk.start_urgency if walk.waiting_at_start else walk.order_urgency
            assert urgency0 is not None
            walks.append((marker, walk, urgency0, trial.time(walk.order_at)))
    rows = []
    for marker, walk, urgency0, order in walks:
        if walk.delivered_at is not None and not walk.lifts:
            msg = (
                f"{fail}: carrier {marker} is delivered {_seconds(walk.delivered_at - trial.start)}"
                " after the start but was lifted before the trial started"
            )
            raise BagError(msg)
        delivered = walk.delivered_at is not None
        last = walk.delivery_urgency if delivered else walk.urgency
        rows.append(
            (
                marker,
                int(urgency0),
                float(order),
                trial.time(walk.lifts[-1]) if walk.lifts else math.nan,
                trial.time(walk.delivered_at) if walk.delivered_at is not None else math.nan,
                walk.delivered_by,
                int(urgency0) if last is None else last,
            )
        )
    return rows


def _check_trials(found: Sequence[Trial], source: str, bag_start: int) -> None:
    """One time unit, and each (condition, run) once."""
    units = {trial.mark.time_unit for trial in found}
    if len(units) > 1:
        first = next(t for t in found if t.mark.time_unit != found[0].mark.time_unit)
        msg = (
            f"{source}: {first.name(bag_start)} has times in {first.mark.time_unit!r} but "
            f"{found[0].name(bag_start)} in {found[0].mark.time_unit!r}; a log has one time unit"
        )
        raise BagError(msg)
    seen: dict[tuple[str, int], Trial] = {}
    for trial in found:
        key = (trial.mark.condition, trial.mark.run)
        if key in seen:
            msg = (
                f"{source}: {trial.name(bag_start)} repeats run {key[1]} of {key[0]} "
                f"(it started {_seconds(seen[key].start - bag_start)} into the bag too); "
                "give each trial its own run index"
            )
            raise BagError(msg)
        seen[key] = trial


def carrier_log(
    found: Sequence[Trial], changes: TagChanges, *, source: str, bag_start: int
) -> CarrierLog:
    """The per-carrier event log of ``found`` from the tag ``changes`` (see the module rules)."""
    _check_trials(found, source, bag_start)
    groups = _by_marker(changes)
    logs = []
    for trial in found:
        fail = f"{source}: {trial.name(bag_start)}"
        rows = _trial_rows(trial, changes, groups, fail)
        columns = list(zip(*rows, strict=True)) if rows else [()] * 7
        run_end = math.nan if trial.end is None else trial.time(trial.end)
        try:
            logs.append(
                CarrierLog(
                    condition=np.full(len(rows), trial.mark.condition, dtype=object).astype(str),
                    run=np.full(len(rows), trial.mark.run, dtype=np.int64),
                    seed=np.full(len(rows), trial.mark.seed, dtype=np.int64),
                    carrier=np.array(columns[0], dtype=np.int64),
                    urgency0=np.array(columns[1], dtype=np.int64),
                    order_time=np.array(columns[2], dtype=np.float64),
                    pickup_time=np.array(columns[3], dtype=np.float64),
                    delivery_time=np.array(columns[4], dtype=np.float64),
                    robot=np.array(columns[5], dtype=np.int64),
                    run_end=np.full(len(rows), run_end),
                    urgency_end=np.array(columns[6], dtype=np.int64),
                    time_unit=trial.mark.time_unit,
                )
            )
        except EventLogError as error:
            msg = f"{fail}: {error}"
            raise BagError(msg) from None
    return CarrierLog.concat(logs)


def event_table(
    found: Sequence[Trial], events: RobotEvents, *, source: str, bag_start: int
) -> EventTable:
    """The long-format event table of ``found``: each trial's events, sorted by time (stably)."""
    _check_trials(found, source, bag_start)
    order = np.argsort(events.time, kind="stable")
    times = events.time[order]
    tables = []
    for trial in found:
        low = int(np.searchsorted(times, trial.start, side="left"))
        high = int(np.searchsorted(times, trial.until, side="right"))
        rows = order[low:high]
        count = len(rows)
        try:
            tables.append(
                EventTable(
                    condition=np.full(count, trial.mark.condition, dtype=object).astype(str),
                    seed=np.full(count, trial.mark.seed, dtype=np.int64),
                    run=np.full(count, trial.mark.run, dtype=np.int64),
                    time=np.array([trial.time(int(events.time[r])) for r in rows], dtype=float),
                    kind=np.array([events.kind[r] for r in rows], dtype=str)
                    if count
                    else np.zeros(0, dtype=str),
                    carrier=events.carrier[rows],
                    robot=events.robot[rows],
                    value=events.value[rows],
                    time_unit=trial.mark.time_unit,
                )
            )
        except EventLogError as error:
            msg = f"{source}: {trial.name(bag_start)}: {error}"
            raise BagError(msg) from None
    return EventTable.concat(tables)
