"""CSV reading and writing of the event-log tables, as a spreadsheet writes and reads them.

Reading tolerates a UTF-8 byte-order mark, CRLF line endings, white space
around cells and header names, header names in any case, blank rows,
semicolon- or tab-separated files, and extra columns (ignored). Messages name
the file, the line of the file (the header is line 1, so this is the row
number a spreadsheet shows) and the column. What a number cell may look like,
and what else is refused (NUL bytes, FIFOs), is in ``swarmtag.io.validation``.

Writing is canonical, so identical tables give byte-identical files: UTF-8
without a byte-order mark, LF line endings, comma-separated, the schema's
columns in order (then each optional column that has a value, e.g.
``run_end``, then ``time_unit`` when the table states one), integers in
decimal, numbers as Python's ``repr`` of the float (the shortest text that
reads back to the same float: ``12.0``, ``0.1``, ``1e-05``), empty cells for
"never"/"none".
"""

from __future__ import annotations

import csv
import io
import math
import os
from collections.abc import Iterable, Sequence
from typing import TypeVar

import numpy as np
from numpy.typing import NDArray

from swarmtag._atomic import atomic_write_bytes
from swarmtag._checks import check_path_value, check_text
from swarmtag.errors import EventLogError
from swarmtag.io.schema import (
    MISSING_ID,
    TIME_UNIT_COLUMN,
    TIME_UNITS,
    ColumnSpec,
    Kind,
    RowLocator,
    finish_text,
    shown,
)
from swarmtag.io.tables import CarrierLog, EventTable, _Columns, check_table
from swarmtag.io.validation import (
    check_no_nul,
    input_file,
    parse_float_cells,
    parse_int_cells,
    reading,
)

__all__ = [
    "format_csv",
    "parse_carrier_csv",
    "parse_event_csv",
    "read_carrier_csv",
    "read_event_csv",
    "write_csv",
]

_TableT = TypeVar("_TableT", bound=_Columns)
_DELIMITERS = (",", ";", "\t")


def _parse_column(
    spec: ColumnSpec, cells: NDArray[np.str_], loc: RowLocator
) -> NDArray[np.generic]:
    present = cells != ""
    if spec.kind is Kind.TEXT:
        return finish_text(spec, cells, loc)
    if spec.kind is Kind.INT:
        return parse_int_cells(spec, cells, present, loc)
    return parse_float_cells(spec, cells, present, loc)


def _parse_time_unit(cells: NDArray[np.str_], loc: RowLocator) -> str | None:
    """The log's one time unit: empty cells are allowed, stated ones must agree."""
    units = np.char.lower(cells)
    stated = np.flatnonzero(units != "")
    if stated.size == 0:
        return None
    first = int(stated[0])
    unit = str(units[first])
    if unit not in TIME_UNITS:
        raise loc.error(
            first,
            TIME_UNIT_COLUMN,
            f"{shown(str(cells[first]))} is not tick or s (simulator ticks or seconds)",
        )
    differ = stated[units[stated] != unit]
    if differ.size:
        index = int(differ[0])
        raise loc.error(
            index,
            TIME_UNIT_COLUMN,
            f"{shown(str(cells[index]))} differs from {unit!r} on {loc.where(first)}; "
            "a log has one time unit",
        )
    return unit


def _rows(text: str, loc: RowLocator) -> tuple[list[str], int, list[list[str]], list[int]]:
    """Header (stripped, lower case), its line, data rows (stripped cells) and their lines.

    A row's line is the line it starts on (a quoted cell may span lines).
    """
    first_line = next((line for line in io.StringIO(text) if line.strip()), "")
    delimiter = next((d for d in _DELIMITERS if d in first_line), ",")
    reader = csv.reader(io.StringIO(text, newline=""), delimiter=delimiter)
    header: list[str] | None = None
    header_line = 1
    rows: list[list[str]] = []
    lines: list[int] = []
    consumed = 0
    try:
        for raw in reader:
            start, consumed = consumed + 1, reader.line_num
            cells = [cell.strip() for cell in raw]
            if not any(cells):
                continue  # blank row, as spreadsheets leave at the end
            if header is None:
                header = [cell.lower() for cell in cells]
                header_line = start
                continue
            rows.append(cells)
            lines.append(start)
    except csv.Error as error:
        raise loc.table_error(f"line {consumed + 1}: not valid CSV ({error})") from None
    if header is None:
        raise loc.table_error("is empty; expected a header line naming the columns")
    return header, header_line, rows, lines


def _parse_table(text: str, table: type[_TableT], source: str | None) -> _TableT:
    loc = RowLocator(source=source)
    header, header_line, rows, line_numbers = _rows(text, loc)
    if "\x00" in text:
        check_no_nul(
            header, header_line, rows, RowLocator(source=source, lines=np.asarray(line_numbers))
        )
    named = [name for name in header if name]
    repeated = sorted({name for name in named if named.count(name) > 1})
    if repeated:
        raise loc.table_error(f"line {header_line} names column {repeated[0]} more than once")
    missing = [spec.name for spec in table.SCHEMA if spec.name not in header]
    if missing:
        raise loc.table_error(
            f"line {header_line} lacks column{'s' if len(missing) > 1 else ''} "
            f"{', '.join(missing)}; "
            f"an event log has columns {', '.join(spec.name for spec in table.SCHEMA)}"
        )
    loc = RowLocator(source=source, lines=np.asarray(line_numbers, dtype=np.int64))
    width = len(header)
    for index, cells in enumerate(rows):
        if len(cells) > width:
            if any(cells[width:]):
                raise loc.table_error(
                    f"{loc.where(index)} has {len(cells)} cells but the header names {width} "
                    "columns (a comma inside a value? quote it)"
                )
            del cells[width:]
        elif len(cells) < width:
            cells.extend([""] * (width - len(cells)))
    by_name = {name: position for position, name in enumerate(header) if name}

    def cells_of(name: str) -> NDArray[np.str_]:
        position = by_name[name]
        return np.array([cells[position] for cells in rows], dtype=str)

    columns = {
        spec.name: _parse_column(spec, cells_of(spec.name), loc)
        for spec in table.all_columns()
        if spec.name in by_name
    }
    time_unit = (
        _parse_time_unit(cells_of(TIME_UNIT_COLUMN), loc) if TIME_UNIT_COLUMN in by_name else None
    )
    return table._build(columns, time_unit, loc)


def _read_text(path: str | os.PathLike[str], what: str) -> str:
    """The file's text; a FIFO, a folder or a device is refused before it is opened."""
    checked = input_file(path, what)
    name = os.fspath(path)
    with reading(name):
        try:
            with checked.open(encoding="utf-8-sig", newline="") as handle:
                return handle.read()
        except UnicodeDecodeError as error:
            raise EventLogError(
                f"{name}: not UTF-8 text (byte {error.start}); save the file as CSV UTF-8"
            ) from None
        except OSError as error:
            raise EventLogError(f"{name}: cannot read ({error.strerror})") from None


def parse_carrier_csv(text: str, *, source: str | None = None) -> CarrierLog:
    """Read a per-carrier event log from CSV text; ``source`` names it in messages.

    >>> text = '''condition,run,seed,carrier,urgency0,order_time,pickup_time,delivery_time,robot
    ... proximity,0,0,4,7,-3.5,10,25.5,1
    ... proximity,0,0,5,2,-1.0,,,
    ... '''
    >>> parse_carrier_csv(text).delivery_time
    array([25.5,  nan])
    >>> parse_carrier_csv(text.replace("25.5", "abc"), source="events.csv")
    Traceback (most recent call last):
    ...
    swarmtag.errors.EventLogError: events.csv: line 2, column delivery_time: 'abc' is not a number
    """
    text, source = _check_text_source(text, source)
    with reading(source):
        return _parse_table(text.removeprefix("\ufeff"), CarrierLog, source)


def parse_event_csv(text: str, *, source: str | None = None) -> EventTable:
    """Read a long-format event table from CSV text; ``source`` names it in messages."""
    text, source = _check_text_source(text, source)
    with reading(source):
        return _parse_table(text.removeprefix("\ufeff"), EventTable, source)


def _check_text_source(text: object, source: object) -> tuple[str, str | None]:
    """The public parsers' arguments, checked at the entry."""
    checked = check_text("text", text, error=EventLogError)
    return checked, None if source is None else check_text("source", source, error=EventLogError)


def read_carrier_csv(path: str | os.PathLike[str]) -> CarrierLog:
    """Read a per-carrier event log from a CSV file."""
    path = check_path_value("path", path, error=EventLogError)
    return parse_carrier_csv(_read_text(path, "CSV event log"), source=os.fspath(path))


def read_event_csv(path: str | os.PathLike[str]) -> EventTable:
    """Read a long-format event table from a CSV file."""
    path = check_path_value("path", path, error=EventLogError)
    return parse_event_csv(_read_text(path, "CSV event table"), source=os.fspath(path))


def _format_column(spec: ColumnSpec, column: NDArray[np.generic]) -> list[str]:
    values = column.tolist()
    if spec.kind is Kind.TEXT:
        return [str(value) for value in values]
    if spec.kind is Kind.INT:
        return ["" if value == MISSING_ID and spec.nullable else str(value) for value in values]
    return ["" if math.isnan(value) else repr(value) for value in values]


def _format_rows(table: _Columns) -> tuple[list[str], Iterable[Sequence[str]]]:
    specs = table.written_columns()
    header = [spec.name for spec in specs]
    cells = [_format_column(spec, getattr(table, spec.name)) for spec in specs]
    if table.time_unit is not None:
        header.append(TIME_UNIT_COLUMN)
        cells.append([table.time_unit] * len(table))
    return header, zip(*cells, strict=True)


def format_csv(table: CarrierLog | EventTable) -> str:
    """The canonical CSV text of a table (see the module docstring for the format).

    >>> log = CarrierLog(condition=["proximity"], run=[0], seed=[0], carrier=[4], urgency0=[7],
    ...     order_time=[-3.5], pickup_time=[10.0], delivery_time=[25.5], robot=[1])
    >>> print(format_csv(log), end="")
    condition,run,seed,carrier,urgency0,order_time,pickup_time,delivery_time,robot
    proximity,0,0,4,7,-3.5,10.0,25.5,1
    """
    check_table("table", table)
    buffer = io.StringIO(newline="")
    writer = csv.writer(buffer, lineterminator="\n")
    header, rows = _format_rows(table)
    writer.writerow(header)
    writer.writerows(rows)
    return buffer.getvalue()


def write_csv(table: CarrierLog | EventTable, path: str | os.PathLike[str]) -> None:
    """Write a table as canonical CSV (UTF-8, LF line endings)."""
    check_table("table", table)
    path = check_path_value("path", path, error=EventLogError)
    data = format_csv(table).encode("utf-8")
    try:
        atomic_write_bytes(path, data)
    except OSError as error:
        raise EventLogError(f"{os.fspath(path)}: cannot write ({error.strerror})") from None
