"""The columns of the event-log tables (SPEC §8.1) and the checks on their values.

Each table is a tuple of ``ColumnSpec``: one spec drives parsing (CSV cells,
Parquet columns), checking (types and ranges) and writing, so the three never
disagree. Messages name the file, the row and the column, and say what was
expected. Rows are named ``line N`` for CSV files (the line of the file, the
header being line 1, i.e. the row number a spreadsheet shows) and ``row N``
otherwise (the 1-based data row, header not counted).

Value rules every source meets (CSV, Parquet, in memory): integers fit the
column's range (at most int64); times are finite and lie in
``[0, MAX_EVENT_TIME]`` (``order_time``: ``[-MAX_EVENT_TIME, MAX_EVENT_TIME]``,
as SPEC §8.1 lets an order precede the run start) and are 0 or at least
``MIN_NONZERO_TIME`` away from it; other numbers lie within
``MAX_EVENT_VALUE`` of 0; text has no control characters.
"""

from __future__ import annotations

import enum
import re
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Final

import numpy as np
from numpy.typing import ArrayLike, NDArray

from swarmtag.errors import EventLogError

__all__ = [
    "CARRIER_OPTIONAL",
    "CARRIER_SCHEMA",
    "EVENT_SCHEMA",
    "INT64_MAX",
    "MAX_EVENT_TIME",
    "MAX_EVENT_VALUE",
    "MIN_NONZERO_TIME",
    "MISSING_ID",
    "TIME_COLUMNS",
    "TIME_UNITS",
    "TIME_UNIT_COLUMN",
    "ColumnSpec",
    "Kind",
    "RowLocator",
    "check_column",
    "check_text_cells",
    "check_time_unit",
    "finish_float",
    "finish_int",
    "finish_text",
    "shown",
    "too_large",
]

MISSING_ID: Final = -1
"""In-memory value of an empty integer cell (a robot, an event's carrier): "none"."""
TIME_UNITS: Final = ("tick", "s")
"""Allowed values of the optional ``time_unit`` column: simulator ticks or seconds."""
TIME_UNIT_COLUMN: Final = "time_unit"
INT64_MAX: Final = int(np.iinfo(np.int64).max)
"""The largest integer any integer column holds (the columns are int64)."""
MAX_EVENT_TIME: Final = 1e12
"""The largest time (ticks or seconds) a log may hold: 30 000 years of seconds.

Far beyond any run, yet small enough that sums of millions of latencies and
the statistics on them stay finite (a time of 1e308 overflowed them).
"""
MIN_NONZERO_TIME: Final = 1e-9
"""The smallest nonzero time (in size): a nanosecond, or a billionth of a tick.

Finer times carry no meaning; refusing them keeps throughput's
``100 * n / (t_last - t_first)`` finite (two deliveries at 0 and 5e-324 gave inf).
"""
MAX_EVENT_VALUE: Final = 1e12
"""The largest size of a non-time number (an event's ``value``: an urgency, a count)."""


class Kind(enum.Enum):
    """What a column holds; the value is the word used in messages."""

    TEXT = "text"
    INT = "an integer"
    FLOAT = "a number"


@dataclass(frozen=True, slots=True)
class ColumnSpec:
    """One column: its name, kind, whether a cell may be empty, and its range.

    An empty cell means "never" or "none": NaN for numbers, ``MISSING_ID`` for
    integers. Integer columns without a ``maximum`` end at ``INT64_MAX``. A
    ``time`` column's nonzero values are at least ``MIN_NONZERO_TIME`` in size.
    """

    name: str
    kind: Kind
    nullable: bool = False
    minimum: float | None = None
    maximum: float | None = None
    time: bool = False

    def expected(self) -> str:
        """What a valid cell looks like, for messages: ``an integer in 0-9``."""
        text = self.kind.value
        if self.kind is Kind.FLOAT and self.minimum is not None and self.maximum is not None:
            text += f" in [{self.minimum:g}, {self.maximum:g}]"
        elif self.minimum is not None and self.maximum is not None:
            text += f" in {int(self.minimum)}-{int(self.maximum)}"
        elif self.minimum is not None:
            text += f" >= {int(self.minimum)}"
        if self.nullable:
            text += ", or empty"
        return text

    def int_range(self) -> str:
        """The full range of an integer column, int64's end included: ``0-9223372036854775807``."""
        low = -INT64_MAX - 1 if self.minimum is None else int(self.minimum)
        high = INT64_MAX if self.maximum is None else int(self.maximum)
        return f"an integer in {low}-{high}"


CARRIER_SCHEMA: Final = (
    ColumnSpec("condition", Kind.TEXT),
    ColumnSpec("run", Kind.INT, minimum=0),
    ColumnSpec("seed", Kind.INT, minimum=0),
    ColumnSpec("carrier", Kind.INT, minimum=0),
    ColumnSpec("urgency0", Kind.INT, minimum=0, maximum=9),
    ColumnSpec(
        "order_time", Kind.FLOAT, minimum=-MAX_EVENT_TIME, maximum=MAX_EVENT_TIME, time=True
    ),
    ColumnSpec(
        "pickup_time", Kind.FLOAT, nullable=True, minimum=0, maximum=MAX_EVENT_TIME, time=True
    ),
    ColumnSpec(
        "delivery_time", Kind.FLOAT, nullable=True, minimum=0, maximum=MAX_EVENT_TIME, time=True
    ),
    ColumnSpec("robot", Kind.INT, nullable=True, minimum=0),
)
"""The per-carrier table: one row per carrier per run, in the order files carry it."""

CARRIER_OPTIONAL: Final = (
    ColumnSpec("run_end", Kind.FLOAT, nullable=True, minimum=0, maximum=MAX_EVENT_TIME, time=True),
    ColumnSpec("urgency_end", Kind.INT, nullable=True, minimum=0, maximum=9),
)
"""Optional per-carrier columns (extra columns SPEC §8.1 allows), after the schema's in files.

``run_end``: when the run's observation ended (one value per run; the
censoring time of undelivered carriers). ``urgency_end``: the carrier's
urgency when delivered, or at run end if never delivered. Absent or empty
cells are NaN / ``MISSING_ID``; files hold a column only when a cell is set.
"""

EVENT_SCHEMA: Final = (
    ColumnSpec("condition", Kind.TEXT),
    ColumnSpec("seed", Kind.INT, minimum=0),
    ColumnSpec("run", Kind.INT, minimum=0),
    ColumnSpec("time", Kind.FLOAT, minimum=0, maximum=MAX_EVENT_TIME, time=True),
    ColumnSpec("kind", Kind.TEXT),
    ColumnSpec("carrier", Kind.INT, nullable=True, minimum=0),
    ColumnSpec("robot", Kind.INT, nullable=True, minimum=0),
    ColumnSpec(
        "value", Kind.FLOAT, nullable=True, minimum=-MAX_EVENT_VALUE, maximum=MAX_EVENT_VALUE
    ),
)
"""The optional long-format event table: everything else that happened in a run."""

TIME_COLUMNS: Final = tuple(
    spec.name for spec in (*CARRIER_SCHEMA, *CARRIER_OPTIONAL, *EVENT_SCHEMA) if spec.time
)
"""Every column that holds a time: ``order_time``, ``pickup_time``, ``delivery_time``, ..."""


@dataclass(frozen=True, slots=True, eq=False)
class RowLocator:
    """Names rows in messages: ``line N`` of a CSV file, else ``row N`` (1-based data row).

    >>> RowLocator(source="events.csv", lines=np.array([2, 3])).error(1, "run", "oops")
    EventLogError('events.csv: line 3, column run: oops')
    >>> RowLocator().where_many([0, 4])
    'rows 1 and 5'
    """

    source: str | None = None
    lines: NDArray[np.int64] | None = None

    def where(self, index: int) -> str:
        """``line N`` or ``row N`` for the data row at 0-based ``index``."""
        if self.lines is not None:
            return f"line {int(self.lines[index])}"
        return f"row {index + 1}"

    def where_many(self, indices: Sequence[int]) -> str:
        """``lines 8 and 12`` / ``rows 3, 5 and 9``; beyond five, ``rows 1, 2, 3, 4, 5, ...``."""
        shown_rows = list(indices[:5])
        if self.lines is not None:
            word, numbers = "lines", [str(int(self.lines[i])) for i in shown_rows]
        else:
            word, numbers = "rows", [str(i + 1) for i in shown_rows]
        if len(numbers) == 1:
            return f"{word[:-1]} {numbers[0]}"
        if len(indices) > len(shown_rows):
            return f"{word} {', '.join(numbers)}, ... ({len(indices)} in all)"
        return f"{word} {', '.join(numbers[:-1])} and {numbers[-1]}"

    def prefix(self) -> str:
        """``file: `` when the table came from a file, else nothing."""
        return f"{self.source}: " if self.source else ""

    def error(self, index: int, column: str, problem: str) -> EventLogError:
        """An error naming file, row and column."""
        return EventLogError(f"{self.prefix()}{self.where(index)}, column {column}: {problem}")

    def table_error(self, problem: str) -> EventLogError:
        """An error about the table as a whole (a missing column, a wrong column type)."""
        return EventLogError(f"{self.prefix()}{problem}")


def _first(mask: NDArray[np.bool_]) -> int | None:
    hits = np.flatnonzero(mask)
    return int(hits[0]) if hits.size else None


def _empty_error(spec: ColumnSpec, index: int, loc: RowLocator) -> EventLogError:
    return loc.error(index, spec.name, f"is empty; expected {spec.expected()}")


_CONTROL: Final = re.compile("[\x00-\x1f\x7f-\x9f]")
_SHOWN: Final = 40


def shown(text: str) -> str:
    """``text`` quoted for a message, cut to a few dozen characters (a cell may be huge)."""
    return repr(text) if len(text) <= _SHOWN else repr(text[:_SHOWN]) + "..."


def check_text_cells(spec: ColumnSpec, texts: Sequence[str], loc: RowLocator) -> None:
    """Refuse a text cell holding a control character (a NUL byte, a line break, an escape).

    Condition names and event kinds end up in terminals, tables and file
    names, where such characters corrupt the output or hide what is there.
    """
    if not _CONTROL.search("".join(texts)):
        return
    for index, text in enumerate(texts):
        found = _CONTROL.search(text)
        if found:
            char = found.group()
            what = "a NUL byte" if char == "\x00" else f"control character {char!r}"
            raise loc.error(index, spec.name, f"{shown(text)} holds {what}; expected plain text")


def finish_text(spec: ColumnSpec, values: NDArray[np.str_], loc: RowLocator) -> NDArray[np.str_]:
    """Check a text column (already stripped): no empty cell, no control character."""
    bad = _first(values == "")
    if bad is not None:
        raise _empty_error(spec, bad, loc)
    check_text_cells(spec, values.tolist(), loc)
    return values


def too_large(spec: ColumnSpec, shown_value: str) -> str:
    """The message for an integer beyond int64 or the column's range, with the range."""
    return f"{shown_value} is too large; expected {spec.int_range()}"


def _check_filled(spec: ColumnSpec, present: NDArray[np.bool_], loc: RowLocator) -> None:
    """Refuse the first empty cell of a column that may not be empty."""
    if not spec.nullable:
        bad = _first(~present)
        if bad is not None:
            raise _empty_error(spec, bad, loc)


def _outside(
    spec: ColumnSpec, values: NDArray[np.int64] | NDArray[np.float64]
) -> NDArray[np.bool_]:
    """Where ``values`` lie outside the column's range (NaN compares False: inside)."""
    outside = np.zeros(values.shape, dtype=bool)
    if spec.minimum is not None:
        outside |= values < spec.minimum
    if spec.maximum is not None:
        outside |= values > spec.maximum
    return outside


def finish_int(
    spec: ColumnSpec, values: NDArray[np.int64], present: NDArray[np.bool_], loc: RowLocator
) -> NDArray[np.int64]:
    """Check the range of the present integers; fill missing cells with ``MISSING_ID``."""
    _check_filled(spec, present, loc)
    bad = _first(_outside(spec, values) & present)
    if bad is not None:
        raise loc.error(bad, spec.name, f"{int(values[bad])} is not {spec.expected()}")
    return np.where(present, values, MISSING_ID).astype(np.int64)


def finish_float(
    spec: ColumnSpec, values: NDArray[np.float64], present: NDArray[np.bool_], loc: RowLocator
) -> NDArray[np.float64]:
    """Check that the present numbers are finite and in range; fill missing cells with NaN.

    A time column's nonzero values must also be at least ``MIN_NONZERO_TIME`` in size.
    """
    _check_filled(spec, present, loc)
    bad = _first(present & ~np.isfinite(values))
    if bad is not None:
        raise loc.error(bad, spec.name, f"{float(values[bad])!r} is not a finite number")
    bad = _first(present & _outside(spec, values))
    if bad is not None:
        raise loc.error(
            bad, spec.name, f"{float(values[bad])!r} is out of range; expected {spec.expected()}"
        )
    if spec.time:
        bad = _first(present & (values != 0) & (np.abs(values) < MIN_NONZERO_TIME))
        if bad is not None:
            raise loc.error(
                bad,
                spec.name,
                f"{float(values[bad])!r} is too close to 0; a time is 0 or at least "
                f"{MIN_NONZERO_TIME:g} (ticks or seconds) away from it",
            )
    return np.where(present, values, np.nan)


def _wrong_type(spec: ColumnSpec, dtype: np.dtype[np.generic], loc: RowLocator) -> EventLogError:
    return loc.table_error(f"column {spec.name} holds {dtype}; expected {spec.kind.value} per row")


def _check_text(spec: ColumnSpec, arr: NDArray[np.generic], loc: RowLocator) -> NDArray[np.str_]:
    if arr.dtype.kind == "O":
        items = arr.tolist()
        for index, item in enumerate(items):
            if not isinstance(item, str):
                raise loc.error(index, spec.name, f"{item!r} is not {spec.kind.value}")
        check_text_cells(spec, items, loc)  # before numpy drops trailing NUL characters
        arr = arr.astype(str)
    if arr.dtype.kind != "U":
        raise _wrong_type(spec, arr.dtype, loc)
    text = arr.astype(str)
    bad = _first(np.char.strip(text) != text)
    if bad is not None:
        raise loc.error(bad, spec.name, f"{shown(str(text[bad]))} has white space at its ends")
    return finish_text(spec, text, loc)


def _check_python_ints(
    spec: ColumnSpec, arr: NDArray[np.generic], loc: RowLocator
) -> NDArray[np.int64]:
    """An object array of Python integers (numpy's choice for ints beyond int64)."""
    items = arr.tolist()
    for index, item in enumerate(items):
        if not isinstance(item, int) or isinstance(item, bool):
            raise loc.error(index, spec.name, f"{item!r} is not {spec.kind.value}")
        if not -INT64_MAX - 1 <= item <= INT64_MAX:
            raise loc.error(index, spec.name, too_large(spec, str(item)))
    values = np.array(items, dtype=np.int64)
    present = values != MISSING_ID if spec.nullable else np.ones(values.shape, dtype=bool)
    return finish_int(spec, values, present, loc)


def _check_int(spec: ColumnSpec, arr: NDArray[np.generic], loc: RowLocator) -> NDArray[np.int64]:
    if arr.dtype.kind == "O":
        return _check_python_ints(spec, arr, loc)
    if arr.dtype.kind == "f":
        floats = arr.astype(np.float64)
        finite = np.isfinite(floats)
        bad = _first(~finite & ~np.isnan(floats)) if spec.nullable else _first(~finite)
        if bad is None:
            bad = _first(finite & (floats != np.round(floats)))
        if bad is not None:
            raise loc.error(bad, spec.name, f"{float(floats[bad])!r} is not {spec.expected()}")
        bad = _first(finite & (np.abs(floats) >= 2.0**63))
        if bad is not None:
            raise loc.error(bad, spec.name, too_large(spec, repr(float(floats[bad]))))
        values = np.where(finite, floats, 0).astype(np.int64)
        return finish_int(spec, values, finite, loc)
    if arr.dtype.kind == "u":
        unsigned = arr.astype(np.uint64)
        bad = _first(unsigned > INT64_MAX)
        if bad is not None:
            raise loc.error(bad, spec.name, too_large(spec, str(int(unsigned[bad]))))
    elif arr.dtype.kind != "i":
        raise _wrong_type(spec, arr.dtype, loc)
    values = arr.astype(np.int64)
    present = values != MISSING_ID if spec.nullable else np.ones(values.shape, dtype=bool)
    return finish_int(spec, values, present, loc)


def _check_float(
    spec: ColumnSpec, arr: NDArray[np.generic], loc: RowLocator
) -> NDArray[np.float64]:
    if arr.dtype.kind not in "fiu":
        raise _wrong_type(spec, arr.dtype, loc)
    values = arr.astype(np.float64)
    present = ~np.isnan(values) if spec.nullable else np.ones(values.shape, dtype=bool)
    return finish_float(spec, values, present, loc)


def check_column(spec: ColumnSpec, values: ArrayLike, loc: RowLocator) -> NDArray[np.generic]:
    """Turn an in-memory column into its canonical read-only array, or raise ``EventLogError``.

    Text becomes a unicode array, integers int64 (``MISSING_ID`` = none),
    numbers float64 (NaN = never). Integral floats are accepted as integers.

    >>> check_column(CARRIER_SCHEMA[4], [3, 12], RowLocator())
    Traceback (most recent call last):
    ...
    swarmtag.errors.EventLogError: row 2, column urgency0: 12 is not an integer in 0-9
    """
    if spec.kind is Kind.TEXT and not isinstance(values, np.ndarray):
        arr = np.asarray(values, dtype=object)  # numpy would silently turn 3 into "3"
    else:
        arr = np.asarray(values)
    if arr.ndim != 1:
        raise loc.table_error(
            f"column {spec.name} has shape {arr.shape}; expected one value per row"
        )
    if arr.size == 0:  # an empty list has no dtype worth checking
        arr = arr.astype({Kind.TEXT: str, Kind.INT: np.int64, Kind.FLOAT: np.float64}[spec.kind])
    if arr.dtype.kind == "b":
        raise _wrong_type(spec, arr.dtype, loc)
    result: NDArray[np.generic]
    if spec.kind is Kind.TEXT:
        result = _check_text(spec, arr, loc)
    elif spec.kind is Kind.INT:
        result = _check_int(spec, arr, loc)
    else:
        result = _check_float(spec, arr, loc)
    result = result.copy() if np.may_share_memory(result, arr) else result
    result.flags.writeable = False
    return result


def check_time_unit(time_unit: str | None) -> str | None:
    """Accept ``None`` (not stated), ``"tick"`` or ``"s"``."""
    if time_unit is not None and time_unit not in TIME_UNITS:
        raise EventLogError(f"time unit {time_unit!r} is not one of {', '.join(TIME_UNITS)}")
    return time_unit
