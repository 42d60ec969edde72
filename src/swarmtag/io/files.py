"""Reading and writing event-log files by their extension: ``.csv`` or ``.parquet``."""

from __future__ import annotations

import os
from pathlib import Path
from typing import Final

from swarmtag._checks import check_path_value
from swarmtag.errors import EventLogError
from swarmtag.io.csv_format import read_carrier_csv, read_event_csv, write_csv
from swarmtag.io.parquet_format import read_carrier_parquet, read_event_parquet, write_parquet
from swarmtag.io.tables import CarrierLog, EventTable, check_table

__all__ = ["read_event_log", "read_event_table", "write_event_log", "write_event_table"]

_CSV: Final = frozenset({".csv"})
_PARQUET: Final = frozenset({".parquet", ".pq"})


def _format(path: str | os.PathLike[str]) -> str:
    path = check_path_value("path", path, error=EventLogError)
    suffix = Path(path).suffix.lower()
    if suffix in _CSV:
        return "csv"
    if suffix in _PARQUET:
        return "parquet"
    raise EventLogError(
        f"{os.fspath(path)}: unknown event-log format {suffix or '(no extension)'!s}; "
        "expected a .csv or .parquet file"
    )


def read_event_log(path: str | os.PathLike[str]) -> CarrierLog:
    """Read a per-carrier event log (SPEC §8.1) from a ``.csv`` or ``.parquet`` file."""
    if _format(path) == "csv":
        return read_carrier_csv(path)
    return read_carrier_parquet(path)


def write_event_log(log: CarrierLog, path: str | os.PathLike[str]) -> None:
    """Write a per-carrier event log to a ``.csv`` or ``.parquet`` file."""
    check_table("log", log, (CarrierLog,))
    if _format(path) == "csv":
        write_csv(log, path)
    else:
        write_parquet(log, path)


def read_event_table(path: str | os.PathLike[str]) -> EventTable:
    """Read a long-format event table from a ``.csv`` or ``.parquet`` file."""
    if _format(path) == "csv":
        return read_event_csv(path)
    return read_event_parquet(path)


def write_event_table(table: EventTable, path: str | os.PathLike[str]) -> None:
    """Write a long-format event table to a ``.csv`` or ``.parquet`` file."""
    check_table("table", table, (EventTable,))
    if _format(path) == "csv":
        write_csv(table, path)
    else:
        write_parquet(table, path)
