"""The two event-log tables of SPEC §8.1 as columns of numpy arrays.

``CarrierLog`` holds one row per carrier per run (what every KPI is computed
from); ``EventTable`` holds the optional long-format events (selections,
abandoned pursuits, re-prioritisations, breakdowns). Both are immutable,
checked on construction, and built the same way by the simulator (directly)
and by the file readers (with file and line numbers in their messages).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import ClassVar, Self

import numpy as np
from numpy.typing import ArrayLike, NDArray

from swarmtag._checks import check_sequence, show
from swarmtag.errors import EventLogError
from swarmtag.io.schema import (
    CARRIER_OPTIONAL,
    CARRIER_SCHEMA,
    EVENT_SCHEMA,
    MISSING_ID,
    ColumnSpec,
    Kind,
    RowLocator,
    check_column,
    check_time_unit,
)

__all__ = ["CarrierLog", "EventTable"]


def _absent(spec: ColumnSpec, length: int) -> NDArray[np.generic]:
    """An optional column the source did not give: every cell empty (NaN or ``MISSING_ID``)."""
    array: NDArray[np.generic] = (
        np.full(length, MISSING_ID, dtype=np.int64)
        if spec.kind is Kind.INT
        else np.full(length, np.nan)
    )
    array.flags.writeable = False
    return array


class _Columns:
    """Shared behaviour of the two tables: checked columns, length, equality, row selection."""

    SCHEMA: ClassVar[tuple[ColumnSpec, ...]]
    OPTIONAL: ClassVar[tuple[ColumnSpec, ...]] = ()
    """Columns a source may leave out (all cells empty then); after ``SCHEMA`` in files."""
    condition: NDArray[np.str_]
    time_unit: str | None

    @classmethod
    def all_columns(cls) -> tuple[ColumnSpec, ...]:
        """Every column in memory: the schema's, then the optional ones."""
        return cls.SCHEMA + cls.OPTIONAL

    def written_columns(self) -> tuple[ColumnSpec, ...]:
        """The columns a file of this table holds: the schema's, then optional ones with a value.

        So a table without optional values is written exactly as before they existed.
        """
        kept = []
        for spec in self.OPTIONAL:
            column = getattr(self, spec.name)
            empty = column == MISSING_ID if spec.kind is Kind.INT else np.isnan(column)
            if not empty.all():
                kept.append(spec)
        return self.SCHEMA + tuple(kept)

    def _set_columns(
        self, columns: Mapping[str, ArrayLike | None], time_unit: str | None, loc: RowLocator
    ) -> None:
        length: int | None = None
        for spec in self.all_columns():
            given = columns.get(spec.name)
            if given is not None:
                array = check_column(spec, given, loc)
            elif spec in self.OPTIONAL:
                array = _absent(spec, 0 if length is None else length)
            else:
                raise loc.table_error(f"column {spec.name} is missing; it cannot be left out")
            if length is not None and len(array) != length:
                raise loc.table_error(
                    f"column {spec.name} has {len(array)} rows but column "
                    f"{self.SCHEMA[0].name} has {length}"
                )
            length = len(array)
            object.__setattr__(self, spec.name, array)
        object.__setattr__(self, "time_unit", check_time_unit(time_unit))
        self._check_rows(loc)

    def _check_rows(self, loc: RowLocator) -> None:
        """Checks across columns; none by default."""

    @classmethod
    def _build(
        cls, columns: Mapping[str, ArrayLike | None], time_unit: str | None, loc: RowLocator
    ) -> Self:
        """Construct with messages that name a file and its lines (used by the readers)."""
        table = cls.__new__(cls)
        table._set_columns(columns, time_unit, loc)
        return table

    @classmethod
    def concat(cls, tables: Sequence[Self]) -> Self:
        """The rows of ``tables`` one after the other; all must share one time unit."""
        tables = check_sequence("tables", tables, error=EventLogError)
        for table in tables:
            if not isinstance(table, cls):
                msg = f"tables: {show(table)} is not a {cls.__name__}"
                raise EventLogError(msg)
        if not tables:
            raise EventLogError(f"cannot concatenate an empty list of {cls.__name__} tables")
        units = {table.time_unit for table in tables}
        if len(units) > 1:
            shown = ", ".join(sorted(repr(unit) for unit in units))
            raise EventLogError(f"cannot concatenate tables with different time units: {shown}")
        columns = {
            spec.name: np.concatenate([getattr(table, spec.name) for table in tables])
            for spec in cls.all_columns()
        }
        return cls._build(columns, units.pop(), RowLocator())

    def columns(self) -> dict[str, NDArray[np.generic]]:
        """The columns in schema order (optional ones last), as read-only arrays."""
        return {spec.name: getattr(self, spec.name) for spec in self.all_columns()}

    def __len__(self) -> int:
        return len(getattr(self, self.SCHEMA[0].name))

    def take(self, rows: ArrayLike) -> Self:
        """A table of the given rows (integer indices or a boolean mask), in that order."""
        index = np.asarray(rows)
        return self._build(
            {name: column[index] for name, column in self.columns().items()},
            self.time_unit,
            RowLocator(),
        )

    def __eq__(self, other: object) -> bool:
        if type(other) is not type(self):
            return NotImplemented
        assert isinstance(other, _Columns)
        if self.time_unit != other.time_unit or len(self) != len(other):
            return False
        mine, theirs = self.columns(), other.columns()
        return all(
            np.array_equal(mine[name], theirs[name], equal_nan=mine[name].dtype.kind == "f")
            for name in mine
        )

    __hash__ = None  # type: ignore[assignment]  # mutable-looking arrays: not hashable

    def __repr__(self) -> str:
        conditions = tuple(np.unique(self.condition).tolist())
        return (
            f"{type(self).__name__}(rows={len(self)}, conditions={conditions}, "
            f"time_unit={self.time_unit!r})"
        )


@dataclass(frozen=True, eq=False, init=False, repr=False)
class CarrierLog(_Columns):
    """The per-carrier event log (SPEC §8.1): one row per carrier per run, as columns.

    Missing times are NaN, a missing robot is ``MISSING_ID`` (-1). Arrays are
    copied and made read-only. The constructor checks every column's type and
    range (times: see ``swarmtag.io.schema``), that ``order_time <=
    pickup_time <= delivery_time`` where those are set, that a delivered
    carrier has a pickup time and a robot, that no run of a condition lists a
    carrier twice, and that a run has one seed. The optional ``run_end`` (when
    the run's observation ended; NaN if not given) must be one value per run,
    not before any order, pickup or delivery of the run; the optional
    ``urgency_end`` (urgency when delivered, or at run end; ``MISSING_ID`` if
    not given) is 0-9.

    >>> nan = float("nan")
    >>> log = CarrierLog(
    ...     condition=["proximity", "proximity"], run=[0, 0], seed=[7, 7], carrier=[1, 2],
    ...     urgency0=[9, 3], order_time=[-240.0, -80.0], pickup_time=[12.5, nan],
    ...     delivery_time=[30.0, nan], robot=[0, -1], time_unit="s")
    >>> log
    CarrierLog(rows=2, conditions=('proximity',), time_unit='s')
    >>> log.delivery_time
    array([30., nan])
    """

    SCHEMA: ClassVar[tuple[ColumnSpec, ...]] = CARRIER_SCHEMA
    OPTIONAL: ClassVar[tuple[ColumnSpec, ...]] = CARRIER_OPTIONAL

    condition: NDArray[np.str_]
    run: NDArray[np.int64]
    seed: NDArray[np.int64]
    carrier: NDArray[np.int64]
    urgency0: NDArray[np.int64]
    order_time: NDArray[np.float64]
    pickup_time: NDArray[np.float64]
    delivery_time: NDArray[np.float64]
    robot: NDArray[np.int64]
    run_end: NDArray[np.float64]
    urgency_end: NDArray[np.int64]
    time_unit: str | None

    def __init__(
        self,
        *,
        condition: ArrayLike,
        run: ArrayLike,
        seed: ArrayLike,
        carrier: ArrayLike,
        urgency0: ArrayLike,
        order_time: ArrayLike,
        pickup_time: ArrayLike,
        delivery_time: ArrayLike,
        robot: ArrayLike,
        time_unit: str | None = None,
        run_end: ArrayLike | None = None,
        urgency_end: ArrayLike | None = None,
    ) -> None:
        columns = {
            "condition": condition,
            "run": run,
            "seed": seed,
            "carrier": carrier,
            "urgency0": urgency0,
            "order_time": order_time,
            "pickup_time": pickup_time,
            "delivery_time": delivery_time,
            "robot": robot,
            "run_end": run_end,
            "urgency_end": urgency_end,
        }
        self._set_columns(columns, time_unit, RowLocator())

    @property
    def conditions(self) -> tuple[str, ...]:
        """The condition names present, in sorted order."""
        return tuple(str(name) for name in np.unique(self.condition))

    def sorted(self) -> CarrierLog:
        """The same rows ordered by condition, run and carrier (a canonical order for files)."""
        codes = np.unique(self.condition, return_inverse=True)[1]
        return self.take(np.lexsort((self.carrier, self.run, codes)))

    def _check_order(self, loc: RowLocator, later: str, earlier: str, reason: str) -> None:
        """Refuse the first row whose ``later`` time is before its ``earlier`` one (NaN passes)."""
        late: NDArray[np.float64] = getattr(self, later)
        early: NDArray[np.float64] = getattr(self, earlier)
        bad = np.flatnonzero(late < early)  # NaN compares False
        if bad.size:
            i = int(bad[0])
            raise loc.error(
                i, later, f"{float(late[i])!r} is before {earlier} {float(early[i])!r}{reason}"
            )

    def _check_rows(self, loc: RowLocator) -> None:
        delivered = ~np.isnan(self.delivery_time)
        self._check_order(
            loc, "pickup_time", "order_time", "; a carrier is picked up after it is ordered"
        )
        self._check_order(loc, "delivery_time", "order_time", "; a latency cannot be negative")
        bad = np.flatnonzero(delivered & np.isnan(self.pickup_time))
        if bad.size:
            raise loc.error(
                int(bad[0]),
                "pickup_time",
                "is empty but delivery_time is set; a delivered carrier was picked up first",
            )
        self._check_order(loc, "delivery_time", "pickup_time", "")
        bad = np.flatnonzero(delivered & (self.robot < 0))
        if bad.size:
            raise loc.error(
                int(bad[0]), "robot", "is empty but the carrier was delivered; name the robot"
            )
        self._check_keys(loc)
        self._check_run_end(loc)

    def _check_run_end(self, loc: RowLocator) -> None:
        """``run_end`` is one value per run (or empty for all its rows), after its events.

        After its orders too: a carrier ordered after the run ended would get a
        negative censored latency (run end - order time).
        """
        if len(self) == 0 or np.isnan(self.run_end).all():
            return
        names, codes = np.unique(self.condition, return_inverse=True)
        order = np.lexsort((np.arange(len(self)), self.run, codes))
        same_run = (codes[order][1:] == codes[order][:-1]) & (
            self.run[order][1:] == self.run[order][:-1]
        )
        ends = self.run_end[order]
        differs = same_run & ~((ends[1:] == ends[:-1]) | (np.isnan(ends[1:]) & np.isnan(ends[:-1])))
        if differs.any():
            position = int(np.flatnonzero(differs)[0])
            first, second = int(order[position]), int(order[position + 1])

            def shown(row: int) -> str:
                value = float(self.run_end[row])
                return "empty" if np.isnan(value) else repr(value)

            raise loc.error(
                second,
                "run_end",
                f"{shown(second)} differs from run_end {shown(first)} on {loc.where(first)}, "
                f"the same run ({int(self.run[second])} of {names[codes[second]]}); "
                "a run has one run_end",
            )
        for column in ("pickup_time", "delivery_time", "order_time"):
            times = getattr(self, column)
            bad = np.flatnonzero(self.run_end < times)  # NaN on either side compares False
            if bad.size:
                i = int(bad[0])
                why = (
                    "a carrier of a run is ordered before the run ends"
                    if column == "order_time"
                    else "a run ends after its last pickup and delivery"
                )
                raise loc.error(
                    i,
                    "run_end",
                    f"{float(self.run_end[i])!r} is before {column} {float(times[i])!r}; {why}",
                )

    def _check_keys(self, loc: RowLocator) -> None:
        """No run of a condition lists a carrier twice, and each run has a single seed."""
        if len(self) == 0:
            return
        names, codes = np.unique(self.condition, return_inverse=True)
        order = np.lexsort((np.arange(len(self)), self.carrier, self.run, codes))
        same_run = (codes[order][1:] == codes[order][:-1]) & (
            self.run[order][1:] == self.run[order][:-1]
        )
        same_carrier = same_run & (self.carrier[order][1:] == self.carrier[order][:-1])
        if same_carrier.any():
            # Report the group whose repeat comes earliest in the table.
            later = order[1:][same_carrier]
            second = int(later.min())
            key = (codes[second], self.run[second], self.carrier[second])
            rows = np.flatnonzero(
                (codes == key[0]) & (self.run == key[1]) & (self.carrier == key[2])
            )
            count = "two" if rows.size == 2 else str(rows.size)
            raise loc.table_error(
                f"run {int(key[1])} of {names[key[0]]} has {count} rows for carrier "
                f"{int(key[2])} ({loc.where_many(rows.tolist())})"
            )
        other_seed = same_run & (self.seed[order][1:] != self.seed[order][:-1])
        if other_seed.any():
            position = int(np.flatnonzero(other_seed)[0])
            first, second = int(order[position]), int(order[position + 1])
            raise loc.error(
                second,
                "seed",
                f"{int(self.seed[second])} differs from seed {int(self.seed[first])} on "
                f"{loc.where(first)}, the same run ({int(self.run[second])} of "
                f"{names[codes[second]]}); a run has one seed",
            )


@dataclass(frozen=True, eq=False, init=False, repr=False)
class EventTable(_Columns):
    """The optional long-format event table (SPEC §8.1): one row per event.

    ``kind`` names the event (e.g. ``select``, ``abandon``, ``reprioritise``,
    ``breakdown``); ``carrier`` and ``robot`` are ``MISSING_ID`` (-1) where
    the event has none, ``value`` is NaN where it carries no number (for a
    re-prioritisation it is the new urgency).

    >>> EventTable(condition=["proximity"], seed=[0], run=[3], time=[12.0], kind=["select"],
    ...     carrier=[5], robot=[1], value=[float("nan")], time_unit="tick")
    EventTable(rows=1, conditions=('proximity',), time_unit='tick')
    """

    SCHEMA: ClassVar[tuple[ColumnSpec, ...]] = EVENT_SCHEMA

    condition: NDArray[np.str_]
    seed: NDArray[np.int64]
    run: NDArray[np.int64]
    time: NDArray[np.float64]
    kind: NDArray[np.str_]
    carrier: NDArray[np.int64]
    robot: NDArray[np.int64]
    value: NDArray[np.float64]
    time_unit: str | None

    def __init__(
        self,
        *,
        condition: ArrayLike,
        seed: ArrayLike,
        run: ArrayLike,
        time: ArrayLike,
        kind: ArrayLike,
        carrier: ArrayLike,
        robot: ArrayLike,
        value: ArrayLike,
        time_unit: str | None = None,
    ) -> None:
        columns = {
            "condition": condition,
            "seed": seed,
            "run": run,
            "time": time,
            "kind": kind,
            "carrier": carrier,
            "robot": robot,
            "value": value,
        }
        self._set_columns(columns, time_unit, RowLocator())


def check_table(
    name: str, value: object, kinds: tuple[type, ...] = (CarrierLog, EventTable)
) -> None:
    """An ``EventLogError`` naming ``name`` unless ``value`` is one of ``kinds`` (entry check)."""
    if not isinstance(value, kinds):
        allowed = " or ".join(kind.__name__ for kind in kinds)
        msg = f"{name}: {show(value)} is not a {allowed}"
        raise EventLogError(msg)
