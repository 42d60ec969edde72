"""Parquet reading and writing of the event-log tables (needs the ``parquet`` extra).

``pyarrow`` is imported only inside these functions, so the core installs and
imports without it. Files are written with typed columns: text as strings,
integers as int64, numbers as float64, empty cells ("never", "none") as Parquet
nulls, optional columns (``run_end``, ``urgency_end``) only when a cell is set,
and a ``time_unit`` string column when the table states one. Reading accepts
any integer or floating column type (integral floats for integer columns, as
pandas writes them), nulls or NaN for empty cells, optional columns when
present, and ignores extra columns. Messages name the file, the 1-based data row and the column.
Values meet the same rules as CSV cells (ranges, finite times, text without
control characters); a corrupt or non-Parquet file, or a FIFO or folder, is
one ``EventLogError`` line (``swarmtag.io.validation``).
"""

from __future__ import annotations

import importlib
import os
from typing import TYPE_CHECKING, Any, TypeVar

import numpy as np
from numpy.typing import NDArray

from swarmtag._atomic import atomic_path
from swarmtag._checks import check_path_value
from swarmtag.errors import EventLogError
from swarmtag.io.schema import (
    INT64_MAX,
    MISSING_ID,
    TIME_UNIT_COLUMN,
    TIME_UNITS,
    ColumnSpec,
    Kind,
    RowLocator,
    check_text_cells,
    finish_float,
    finish_int,
    finish_text,
    shown,
    too_large,
)
from swarmtag.io.tables import CarrierLog, EventTable, _Columns, check_table
from swarmtag.io.validation import input_file, reading

if TYPE_CHECKING:
    from types import ModuleType

__all__ = ["read_carrier_parquet", "read_event_parquet", "write_parquet"]

_TableT = TypeVar("_TableT", bound=_Columns)
_NEEDS_EXTRA = "Parquet event logs need the 'parquet' extra: pip install 'swarmtag[parquet]'"


def _pyarrow() -> tuple[ModuleType, ModuleType]:
    """``pyarrow`` and ``pyarrow.parquet``, or an error saying how to install them."""
    try:  # an optional extra, imported on first use (and untyped: no stubs to check against)
        pa = importlib.import_module("pyarrow")
        pq = importlib.import_module("pyarrow.parquet")
    except ImportError:
        raise EventLogError(_NEEDS_EXTRA) from None
    return pa, pq


def _column(
    pa: ModuleType,
    spec: ColumnSpec,
    column: Any,  # noqa: ANN401  # a pyarrow ChunkedArray; pyarrow ships no stubs
    loc: RowLocator,
) -> NDArray[np.generic]:
    """One Arrow column as the schema's array, with the same checks as the CSV reader."""
    kind = column.type
    if pa.types.is_dictionary(kind):
        column = column.cast(kind.value_type)
        kind = column.type
    present = ~np.asarray(column.is_null().to_numpy(zero_copy_only=False), dtype=bool)
    if spec.kind is Kind.TEXT:
        if not (pa.types.is_string(kind) or pa.types.is_large_string(kind)):
            raise loc.table_error(f"column {spec.name} has type {kind}; expected text")
        texts = ["" if v is None else v.strip() for v in column.to_pylist()]
        check_text_cells(spec, texts, loc)  # before numpy drops trailing NUL characters
        return finish_text(spec, np.array(texts, dtype=str), loc)
    numeric = pa.types.is_integer(kind) or pa.types.is_floating(kind)
    if not numeric:
        raise loc.table_error(f"column {spec.name} has type {kind}; expected {spec.kind.value}")
    raw = np.asarray(column.fill_null(0).to_numpy(zero_copy_only=False))
    if spec.kind is Kind.FLOAT:
        values = raw.astype(np.float64)
        present &= ~np.isnan(values)
        return finish_float(spec, values, present, loc)
    if raw.dtype.kind == "f":
        present &= ~np.isnan(raw)
        integral = np.isfinite(raw) & (raw == np.round(raw))
        bad = np.flatnonzero(present & ~integral)
        if bad.size:
            index = int(bad[0])
            raise loc.error(index, spec.name, f"{float(raw[index])!r} is not an integer")
        bad = np.flatnonzero(present & (np.abs(raw) >= 2.0**63))
        if bad.size:
            index = int(bad[0])
            raise loc.error(index, spec.name, too_large(spec, repr(float(raw[index]))))
        raw = np.where(present, raw, 0)
    elif raw.dtype.kind == "u":
        bad = np.flatnonzero(raw > INT64_MAX)
        if bad.size:
            raise loc.error(int(bad[0]), spec.name, too_large(spec, str(int(raw[bad[0]]))))
    return finish_int(spec, raw.astype(np.int64), present, loc)


def _read(path: str | os.PathLike[str], table: type[_TableT], what: str) -> _TableT:
    """Read and check a table; any failure is one ``EventLogError`` line naming the file."""
    path = check_path_value("path", path, error=EventLogError)
    pa, pq = _pyarrow()
    source = os.fspath(path)
    checked = input_file(path, what)  # a FIFO or a folder is refused before it is opened
    with reading(source, (pa.ArrowException,)):
        try:
            data = pq.read_table(checked)
        except MemoryError:
            raise
        except (OSError, ValueError, pa.ArrowException) as error:
            detail = (str(error).strip().splitlines() or [type(error).__name__])[0][:200]
            raise EventLogError(f"{source}: not a readable Parquet file ({detail})") from None
        return _columns(pa, data, table, RowLocator(source=source))


def _columns(
    pa: ModuleType,
    data: Any,  # noqa: ANN401  # a pyarrow Table; pyarrow ships no stubs
    table: type[_TableT],
    loc: RowLocator,
) -> _TableT:
    """The checked table built from the columns of an Arrow table."""
    names = [name.strip().lower() for name in data.column_names]
    repeated = sorted({name for name in names if names.count(name) > 1})
    if repeated:
        raise loc.table_error(f"names column {shown(repeated[0])} more than once")
    by_name = dict(zip(names, data.column_names, strict=True))
    missing = [spec.name for spec in table.SCHEMA if spec.name not in by_name]
    if missing:
        raise loc.table_error(
            f"lacks column{'s' if len(missing) > 1 else ''} {', '.join(missing)}; "
            f"an event log has columns {', '.join(spec.name for spec in table.SCHEMA)}"
        )
    columns = {
        spec.name: _column(pa, spec, data.column(by_name[spec.name]), loc)
        for spec in table.all_columns()
        if spec.name in by_name
    }
    time_unit = None
    if TIME_UNIT_COLUMN in by_name:
        units = {
            str(v).strip().lower() for v in data.column(by_name[TIME_UNIT_COLUMN]).to_pylist() if v
        }
        if len(units) > 1:
            listed = ", ".join(
                unit if unit.isprintable() and len(unit) <= 10 else shown(unit)
                for unit in sorted(units)
            )
            raise loc.table_error(
                f"column {TIME_UNIT_COLUMN} holds {listed}; a log has one time unit"
            )
        time_unit = units.pop() if units else None
        if time_unit is not None and time_unit not in TIME_UNITS:
            raise loc.table_error(f"column {TIME_UNIT_COLUMN}: {shown(time_unit)} is not tick or s")
    return table._build(columns, time_unit, loc)


def read_carrier_parquet(path: str | os.PathLike[str]) -> CarrierLog:
    """Read a per-carrier event log from a Parquet file."""
    return _read(path, CarrierLog, "Parquet event log")


def read_event_parquet(path: str | os.PathLike[str]) -> EventTable:
    """Read a long-format event table from a Parquet file."""
    return _read(path, EventTable, "Parquet event table")


def write_parquet(table: CarrierLog | EventTable, path: str | os.PathLike[str]) -> None:
    """Write a table as Parquet with typed columns and nulls for empty cells."""
    check_table("table", table)
    path = check_path_value("path", path, error=EventLogError)
    pa, pq = _pyarrow()
    arrays: dict[str, Any] = {}
    for spec in table.written_columns():
        column = getattr(table, spec.name)
        if spec.kind is Kind.TEXT:
            arrays[spec.name] = pa.array(column.tolist(), type=pa.string())
        elif spec.kind is Kind.INT:
            mask = column == MISSING_ID if spec.nullable else None
            arrays[spec.name] = pa.array(column, type=pa.int64(), mask=mask)
        else:
            arrays[spec.name] = pa.array(column, type=pa.float64(), mask=np.isnan(column))
    if table.time_unit is not None:
        arrays[TIME_UNIT_COLUMN] = pa.array([table.time_unit] * len(table), type=pa.string())
    try:
        with atomic_path(path) as temp:
            pq.write_table(pa.table(arrays), temp)
    except OSError as error:
        raise EventLogError(f"{os.fspath(path)}: cannot write ({error})") from None
