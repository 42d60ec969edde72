"""Event logs on disk and in memory (SPEC §8.1).

``CarrierLog`` is the per-carrier table every KPI is computed from (one row
per carrier per run); ``EventTable`` is the optional long-format table of
everything else that happened. Both read and write CSV (standard library) and
Parquet (the ``parquet`` extra); ``read_event_log`` picks by file extension.
Every refusal is an ``EventLogError`` naming the file, row and column; what is
accepted is listed in ``swarmtag.io.schema`` (values) and
``swarmtag.io.validation`` (files and CSV cells).
"""

from __future__ import annotations

from swarmtag.io.csv_format import (
    format_csv,
    parse_carrier_csv,
    parse_event_csv,
    read_carrier_csv,
    read_event_csv,
    write_csv,
)
from swarmtag.io.files import read_event_log, read_event_table, write_event_log, write_event_table
from swarmtag.io.parquet_format import read_carrier_parquet, read_event_parquet, write_parquet
from swarmtag.io.schema import (
    CARRIER_OPTIONAL,
    CARRIER_SCHEMA,
    EVENT_SCHEMA,
    MAX_EVENT_TIME,
    MAX_EVENT_VALUE,
    MIN_NONZERO_TIME,
    MISSING_ID,
    TIME_COLUMNS,
    TIME_UNIT_COLUMN,
    TIME_UNITS,
    ColumnSpec,
    Kind,
)
from swarmtag.io.tables import CarrierLog, EventTable

__all__ = [
    "CARRIER_OPTIONAL",
    "CARRIER_SCHEMA",
    "EVENT_SCHEMA",
    "MAX_EVENT_TIME",
    "MAX_EVENT_VALUE",
    "MIN_NONZERO_TIME",
    "MISSING_ID",
    "TIME_COLUMNS",
    "TIME_UNITS",
    "TIME_UNIT_COLUMN",
    "CarrierLog",
    "ColumnSpec",
    "EventTable",
    "Kind",
    "format_csv",
    "parse_carrier_csv",
    "parse_event_csv",
    "read_carrier_csv",
    "read_carrier_parquet",
    "read_event_csv",
    "read_event_log",
    "read_event_parquet",
    "read_event_table",
    "write_csv",
    "write_event_log",
    "write_event_table",
    "write_parquet",
]
