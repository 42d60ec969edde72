"""The one gate for event-log input: which files are opened, which cells are numbers.

Every reader (CSV and Parquet, carrier logs and event tables) goes through
here, so a bad file is refused with one ``EventLogError`` line naming the
file (and, where there is one, the row and column), never with a parser's
own exception. The value rules (ranges, times, text) live in
``swarmtag.io.schema``; the rules across columns in ``swarmtag.io.tables``.

Files: only a readable regular file is opened (``swarmtag._inputs.regular_file``):
a FIFO, a device or a folder is refused without opening it, so it cannot
block. A CSV file must be UTF-8 and hold no NUL byte anywhere (not even in an
ignored column).

CSV number cells, after the white space around the cell (as ``str.strip``
sees it) is dropped, must be plain ASCII decimal numbers:

- integers: an optional sign and digits, optionally followed by a point and
  zeros only (``7``, ``-3``, ``+12``, ``007``, ``3.0``, ``3.``), as
  spreadsheets and pandas write them; the value must fit the column's range
  and int64;
- numbers: an optional sign, digits with an optional decimal point (``12``,
  ``-3.5``, ``.5``, ``5.``) and an optional exponent (``1e-05``, ``2.5E+3``).

Refused, although Python's ``float()`` or ``int()`` (or numpy) read them:
``nan``, ``inf``, ``infinity``, digit separators (``1_000``), non-ASCII digits
(Arabic-Indic, full-width), NUL bytes after the digits (numpy drops them),
and integers with an exponent (``1e3``); refused as well is anything else not
of the forms above (``0x10``, ``1 2``, ``1e``, ``3.5`` as an integer). An
empty cell means "never" / "none" where the column allows it.
"""

from __future__ import annotations

import csv
import math
import os
import re
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Final

import numpy as np
from numpy.typing import NDArray

from swarmtag._inputs import regular_file
from swarmtag._resources import check_memory, format_bytes
from swarmtag.errors import EventLogError
from swarmtag.io.schema import (
    INT64_MAX,
    ColumnSpec,
    RowLocator,
    finish_float,
    finish_int,
    shown,
    too_large,
)

__all__ = [
    "FLOAT_CELL",
    "INT_CELL",
    "check_no_nul",
    "input_file",
    "parse_float_cells",
    "parse_int_cells",
    "reading",
]

INT_CELL: Final = re.compile(r"(?>[+-]?[0-9]+(?:\.0*)?)")
"""An integer cell: sign, digits, and optionally a point followed only by zeros (``3.0``)."""
FLOAT_CELL: Final = re.compile(r"(?>[+-]?(?:[0-9]+(?:\.[0-9]*)?|\.[0-9]+)(?:[eE][+-]?[0-9]+)?)")
"""A number cell: sign, decimal digits with an optional point, an optional exponent.

Atomic groups (``(?>...)``) keep matching linear in the length of the text.
"""
_INT64_DIGITS: Final = len(str(INT64_MAX))
_DETAIL: Final = 200
"""The most characters of a parser's own message quoted in ours."""

_READ_ERRORS: Final = (
    csv.Error,
    UnicodeError,
    ValueError,
    TypeError,
    OverflowError,
    IndexError,
    KeyError,
    NotImplementedError,
    RecursionError,
    OSError,
)
"""What a parser may raise on hostile content (pyarrow's errors derive from these too)."""


BYTES_PER_FILE_BYTE: Final = {"csv": 24, "parquet": 64}
"""Peak memory per byte of an event-log file while it is read and checked (tracemalloc:
17-22 for CSV, the text, its cells as numpy strings and the columns; 42-53 for compressed
Parquet; docs/reliability.md)."""


def input_file(path: str | os.PathLike[str], what: str) -> Path:
    """``path`` if it is a readable regular file, else an ``EventLogError`` saying why.

    ``what`` names the file in messages (``"CSV event log"``). The file is not
    opened, so a FIFO cannot block the reader.
    """
    if not os.path.lexists(path):
        raise EventLogError(f"{os.fspath(path)}: no such file")
    checked = regular_file(path, what=what, error=EventLogError)
    size = checked.stat().st_size
    kind = "parquet" if checked.suffix.lower() in {".parquet", ".pq"} else "csv"
    check_memory(f"{os.fspath(path)} ({format_bytes(size)})", size * BYTES_PER_FILE_BYTE[kind])
    return checked


@contextmanager
def reading(source: str | None, extra: tuple[type[BaseException], ...] = ()) -> Iterator[None]:
    """Turn any error a parser raises on bad content into one ``EventLogError`` line.

    ``EventLogError`` passes through; ``extra`` adds exception types (pyarrow's base).
    """
    prefix = f"{source}: " if source else ""
    caught: tuple[type[BaseException], ...] = (*_READ_ERRORS, *extra)
    try:
        yield
    except EventLogError:
        raise
    except MemoryError:
        raise EventLogError(f"{prefix}too large to read (out of memory)") from None
    except caught as error:
        lines = str(error).strip().splitlines()
        detail = lines[0][:_DETAIL] if lines else type(error).__name__
        raise EventLogError(f"{prefix}cannot read it ({detail})") from error


def _column_name(header: list[str], position: int) -> str:
    if position < len(header) and header[position]:
        return header[position]
    return f"{position + 1} (unnamed)"


def check_no_nul(
    header: list[str], header_line: int, rows: list[list[str]], loc: RowLocator
) -> None:
    """Refuse a NUL byte in any cell of a CSV file, naming its line and column."""
    for position, name in enumerate(header):
        if "\x00" in name:
            raise loc.table_error(
                f"line {header_line}, column {position + 1} of the header holds a NUL byte; "
                "a CSV event log is text"
            )
    for index, cells in enumerate(rows):
        for position, cell in enumerate(cells):
            if "\x00" in cell:
                raise loc.error(
                    index,
                    _column_name(header, position),
                    f"{shown(cell)} holds a NUL byte; a CSV event log is text",
                )


def _joined(pattern: re.Pattern[str]) -> re.Pattern[str]:
    """``pattern`` repeated, NUL-separated: one match checks a whole column."""
    return re.compile(f"{pattern.pattern}(?:\x00{pattern.pattern})*")


_COLUMN_OF: Final = {INT_CELL: _joined(INT_CELL), FLOAT_CELL: _joined(FLOAT_CELL)}


def _first_mismatch(pattern: re.Pattern[str], texts: list[str]) -> int | None:
    """The index of the first text ``pattern`` does not match wholly, or ``None``.

    One regular-expression pass over the joined texts (NUL-separated: the CSV
    reader has refused NUL bytes) keeps this fast for large columns.
    """
    if not texts or _COLUMN_OF[pattern].fullmatch("\x00".join(texts)):
        return None
    return next(i for i, text in enumerate(texts) if not pattern.fullmatch(text))


def _plain_cells(
    spec: ColumnSpec,
    cells: NDArray[np.str_],
    present: NDArray[np.bool_],
    loc: RowLocator,
    *,
    pattern: re.Pattern[str],
    why: Callable[[str], str],
) -> tuple[NDArray[np.intp], list[str]]:
    """The rows and texts of the present cells; the first not matching ``pattern`` is refused.

    ``why(text)`` says what is wrong with that cell.
    """
    rows = np.flatnonzero(present)
    texts: list[str] = cells[present].tolist()
    bad = _first_mismatch(pattern, texts)
    if bad is not None:
        raise loc.error(int(rows[bad]), spec.name, why(texts[bad]))
    return rows, texts


def parse_int_cells(
    spec: ColumnSpec, cells: NDArray[np.str_], present: NDArray[np.bool_], loc: RowLocator
) -> NDArray[np.int64]:
    """The integers of a CSV column (see the module docstring for the accepted forms)."""
    rows, texts = _plain_cells(
        spec, cells, present, loc, pattern=INT_CELL, why=lambda t: f"{shown(t)} is not an integer"
    )
    given = cells[present]
    heads = texts
    if any("." in text for text in texts):  # "3.0": keep the part before the point
        heads = [text.partition(".")[0] for text in texts]
        given = np.array(heads, dtype=str)
    values = np.zeros(cells.shape, dtype=np.int64)
    try:
        values[present] = given.astype(np.int64)
    except (ValueError, OverflowError):
        for index, head in zip(rows.tolist(), heads, strict=True):
            digits = head.lstrip("+-").lstrip("0") or "0"
            sign = "-" if head.startswith("-") else ""
            number = int(sign + digits) if len(digits) <= _INT64_DIGITS else None
            if number is None or not -INT64_MAX - 1 <= number <= INT64_MAX:
                problem = too_large(spec, shown(str(cells[index])))
                raise loc.error(index, spec.name, problem) from None
            values[index] = number
    return finish_int(spec, values, present, loc)


def _not_a_number(text: str) -> str:
    """Why a cell is not a plain number; ``nan`` and ``inf`` get a message of their own."""
    try:
        number = float(text)
    except ValueError:
        number = 0.0
    if not math.isfinite(number):
        return f"{shown(text)} is not a finite number; write a plain number, or leave it empty"
    return f"{shown(text)} is not a number"


def parse_float_cells(
    spec: ColumnSpec, cells: NDArray[np.str_], present: NDArray[np.bool_], loc: RowLocator
) -> NDArray[np.float64]:
    """The numbers of a CSV column (see the module docstring for the accepted forms)."""
    _, texts = _plain_cells(spec, cells, present, loc, pattern=FLOAT_CELL, why=_not_a_number)
    values = np.full(cells.shape, np.nan)
    values[present] = np.array(texts, dtype=str).astype(np.float64)
    overflow = np.flatnonzero(present & ~np.isfinite(values))  # a plain number like 1e400
    if overflow.size:
        index = int(overflow[0])
        raise loc.error(
            index,
            spec.name,
            f"{shown(str(cells[index]))} is out of range; expected {spec.expected()}",
        )
    return finish_float(spec, values, present, loc)
