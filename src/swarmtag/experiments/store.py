"""The results store: every simulated run of every study, in one embedded DuckDB file.

A run is identified by its **key** (study, scale, condition, master seed,
run, code version). The store has three tables:

- ``runs``: one row per stored run, the key as primary key (so a run can
  never be stored twice);
- ``carriers``: the run's carrier-log rows (SPEC §8.1) with the key and the
  row's position ``row`` in the simulated log;
- ``events``: the run's event-table rows, likewise.

``write_chunk`` stores a chunk of runs (their ``runs`` rows and all their
carrier and event rows) in **one transaction**: a process killed at any
moment leaves each run stored completely or not at all, and ``missing_runs``
tells the runner what is left to compute. ``load_log`` reads rows back in
their simulated order, so a stored log is byte-identical (as CSV) to the
simulated one. Missing times are stored as SQL ``NULL`` (NaN in memory), a
missing robot as ``NULL`` (-1 in memory); so are the optional carrier columns
``run_end`` and ``urgency_end`` where a log has none. A store created before
those columns existed gains them (as ``NULL``) when opened for writing, and
reads as if they were ``NULL`` when opened read-only.

DuckDB is imported lazily (the ``experiments`` extra). One process writes a
store at a time (DuckDB locks the file); workers never touch it.
"""

from __future__ import annotations

import contextlib
import os
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from pathlib import Path
from types import ModuleType, TracebackType
from typing import Any, Final, Self

import numpy as np

from swarmtag._atomic import write_failure_in_text
from swarmtag._checks import check_bool, check_path_value
from swarmtag._interrupt import deferred
from swarmtag.errors import StoreError
from swarmtag.io import CarrierLog, EventTable, write_event_log, write_event_table

__all__ = ["KEY_COLUMNS", "SCHEMA_SQL", "ResultsStore", "RunKey", "export_logs"]

KEY_COLUMNS: Final = ("study", "scale", "condition", "seed", "run", "code_version")
"""The columns that identify a run, in every table."""

SCHEMA_SQL: Final = """
CREATE TABLE IF NOT EXISTS runs (
    study VARCHAR NOT NULL, scale VARCHAR NOT NULL, condition VARCHAR NOT NULL,
    seed BIGINT NOT NULL, run BIGINT NOT NULL, code_version VARCHAR NOT NULL,
    carrier_rows BIGINT NOT NULL, event_rows BIGINT NOT NULL, time_unit VARCHAR,
    PRIMARY KEY (study, scale, condition, seed, run, code_version)
);
CREATE TABLE IF NOT EXISTS carriers (
    study VARCHAR NOT NULL, scale VARCHAR NOT NULL, condition VARCHAR NOT NULL,
    seed BIGINT NOT NULL, run BIGINT NOT NULL, code_version VARCHAR NOT NULL,
    "row" BIGINT NOT NULL, carrier BIGINT NOT NULL, urgency0 BIGINT NOT NULL,
    order_time DOUBLE NOT NULL, pickup_time DOUBLE, delivery_time DOUBLE, robot BIGINT,
    run_end DOUBLE, urgency_end BIGINT
);
ALTER TABLE carriers ADD COLUMN IF NOT EXISTS run_end DOUBLE;
ALTER TABLE carriers ADD COLUMN IF NOT EXISTS urgency_end BIGINT;
CREATE TABLE IF NOT EXISTS events (
    study VARCHAR NOT NULL, scale VARCHAR NOT NULL, condition VARCHAR NOT NULL,
    seed BIGINT NOT NULL, run BIGINT NOT NULL, code_version VARCHAR NOT NULL,
    "row" BIGINT NOT NULL, time DOUBLE NOT NULL, kind VARCHAR NOT NULL,
    carrier BIGINT, robot BIGINT, value DOUBLE
);
"""
"""The store's tables (created on first open; older stores gain the optional carrier columns)."""

_OPTIONAL_CARRIER_COLUMNS: Final = {"run_end": "DOUBLE", "urgency_end": "BIGINT"}
"""Carrier columns added after the first schema: nullable, possibly absent from an old store."""

_NEEDS_EXTRA: Final = (
    "the results store needs the 'experiments' extra: pip install 'swarmtag[experiments]'"
)


def _duckdb() -> ModuleType:
    """The duckdb module; a Ctrl-C while it loads is raised once it has loaded.

    duckdb's native module builds Python enums as it loads: a Ctrl-C raised
    in one of them is a fatal error for its bindings (nanobind), which abort
    the process (exit -6, a traceback) instead of ending it with "aborted".
    """
    try:
        with deferred():
            import duckdb  # noqa: PLC0415 - optional extra, imported on first use
    except ImportError:  # pragma: no cover - the extra is installed in the test environment
        raise StoreError(_NEEDS_EXTRA) from None
    return duckdb


@dataclass(frozen=True, kw_only=True)
class RunKey:
    """The fixed part of a run's key: the study, scale, master seed and code version of a chunk.

    The condition and the run index complete it.
    """

    study: str
    scale: str
    seed: int
    code_version: str

    def params(self) -> list[Any]:
        """The key's values in the order of the ``WHERE`` clauses below."""
        return [self.study, self.scale, self.seed, self.code_version]


# Every query passes the key's values as parameters, never as text.
_STORED_RUNS: Final = (
    "SELECT run FROM runs "
    "WHERE study = ? AND scale = ? AND seed = ? AND code_version = ? AND condition = ?"
)
_CARRIER_ROWS: Final = (
    "SELECT condition, run, seed, carrier, urgency0, order_time, pickup_time, "
    "delivery_time, coalesce(robot, -1), {run_end}, coalesce({urgency_end}, -1) FROM carriers "
    "WHERE study = ? AND scale = ? AND seed = ? AND code_version = ? "
    'AND condition = ? AND run < ? ORDER BY run, "row"'
)
_EVENT_ROWS: Final = (
    "SELECT condition, seed, run, time, kind, coalesce(carrier, -1), coalesce(robot, -1), "
    "value FROM events "
    "WHERE study = ? AND scale = ? AND seed = ? AND code_version = ? "
    'AND condition = ? AND run < ? ORDER BY run, "row"'
)
_TIME_UNITS: Final = (
    "SELECT DISTINCT time_unit FROM runs "
    "WHERE study = ? AND scale = ? AND seed = ? AND code_version = ? "
    "AND list_contains(?, condition) AND run < ?"
)


def _nullable_ids(values: np.ndarray[Any, Any]) -> np.ndarray[Any, Any]:
    """Integer ids with -1 ("none") as a masked NULL: a float column DuckDB reads as NULL."""
    out = values.astype(np.float64)
    out[values < 0] = np.nan
    return out


class ResultsStore:
    """A DuckDB results store at ``path`` (created if absent); use as a context manager.

    ``read_only=True`` opens an existing store for reading only. DuckDB lets
    one process at a time open a file for writing, and none read it meanwhile.
    """

    def __init__(self, path: str | os.PathLike[str], *, read_only: bool = False) -> None:
        checked = check_path_value("path", path, error=StoreError)
        check_bool("read_only", read_only, error=StoreError)
        duckdb = _duckdb()
        self.path = Path(checked)
        if read_only and not self.path.is_file():
            msg = f"{self.path}: no results store there"
            raise StoreError(msg)
        try:
            # A DuckDBPyConnection; typed Any as duckdb's stubs vary between releases.
            self._con: Any = duckdb.connect(str(self.path), read_only=read_only)
        except duckdb.Error as error:
            raise self._failed("cannot open the results store", error, kept=False) from None
        try:
            if not read_only:
                self._con.execute(SCHEMA_SQL)
            self._carrier_rows = _CARRIER_ROWS.format(**self._optional_carrier_columns())
        except duckdb.Error as error:  # a full disk as the tables are made
            self._con.close()
            raise self._failed("cannot prepare the results store", error, kept=False) from None
        except BaseException:  # Ctrl-C included: no open handle (nor .wal) left behind
            self._con.close()
            raise

    def _failed(self, what: str, error: Exception, *, kept: bool = True) -> StoreError:
        """One line for a DuckDB error: the device's refusal by its name, else DuckDB's words.

        A device that refused a write (full, over quota, read-only) is said
        as everywhere else; what was committed before stays, so the same
        command resumes once there is room.
        """
        text = " ".join(str(error).split())
        failure = write_failure_in_text(text, self.path)
        if failure is not None and kept:
            return StoreError(f"{failure}; the runs stored before are kept (run again to resume)")
        if failure is not None:
            return StoreError(str(failure))
        return StoreError(f"{self.path}: {what} ({text})")

    def _optional_carrier_columns(self) -> dict[str, str]:
        """SQL for each optional carrier column: its name, or a typed NULL in an older store."""
        present = {
            str(row[0])
            for row in self._con.execute(
                "SELECT column_name FROM duckdb_columns() WHERE table_name = 'carriers'"
            ).fetchall()
        }
        return {
            name: name if name in present else f"CAST(NULL AS {kind})"
            for name, kind in _OPTIONAL_CARRIER_COLUMNS.items()
        }

    def close(self) -> None:
        """Close the connection (committed chunks are already on disk)."""
        self._con.close()

    def __enter__(self) -> Self:
        return self

    def __exit__(
        self,
        kind: type[BaseException] | None,
        error: BaseException | None,
        trace: TracebackType | None,
    ) -> None:
        self.close()

    # -- writing ---------------------------------------------------------------------------

    def write_chunk(self, key: RunKey, carriers: CarrierLog, events: EventTable) -> int:
        """Store the runs of one simulated chunk, all or nothing; return how many runs it held.

        ``carriers`` and ``events`` are one condition's logs of those runs,
        as ``simulate`` returns them. A run already stored under the same key
        is a ``StoreError`` (the runner only computes missing runs).
        """
        conditions = set(carriers.condition.tolist()) | set(events.condition.tolist())
        if len(conditions) != 1:
            msg = f"write_chunk: a chunk holds one condition, got {sorted(conditions)}"
            raise StoreError(msg)
        condition = conditions.pop()
        if len(events) and events.time_unit != carriers.time_unit:
            msg = (
                f"write_chunk: event time unit {events.time_unit!r} differs from the "
                f"carrier log's {carriers.time_unit!r}"
            )
            raise StoreError(msg)
        run_ids = np.unique(carriers.run)
        prefix = [key.study, key.scale, condition]
        carrier_rows = _positions(carriers.run)
        event_rows = _positions(events.run)
        carrier_frame = {
            "run": carriers.run,
            "row": carrier_rows,
            "carrier": carriers.carrier,
            "urgency0": carriers.urgency0,
            "order_time": carriers.order_time,
            "pickup_time": carriers.pickup_time,
            "delivery_time": carriers.delivery_time,
            "robot": _nullable_ids(carriers.robot),
            "run_end": carriers.run_end,
            "urgency_end": _nullable_ids(carriers.urgency_end),
        }
        event_frame = {
            "run": events.run,
            "row": event_rows,
            "time": events.time,
            "kind": events.kind,
            "carrier": _nullable_ids(events.carrier),
            "robot": _nullable_ids(events.robot),
            "value": events.value,
        }
        run_frame = {
            "run": run_ids,
            "carrier_rows": np.array([(carriers.run == r).sum() for r in run_ids], np.int64),
            "event_rows": np.array([(events.run == r).sum() for r in run_ids], np.int64),
        }
        duckdb = _duckdb()
        con = self._con
        try:
            con.execute("BEGIN TRANSACTION")
            con.register("chunk_runs", run_frame)
            con.register("chunk_carriers", carrier_frame)
            con.register("chunk_events", event_frame)
            con.execute(
                "INSERT INTO runs SELECT ?, ?, ?, ?, run, ?, carrier_rows, event_rows, ? "
                "FROM chunk_runs",
                [*prefix, key.seed, key.code_version, carriers.time_unit],
            )
            # The key's constant columns are parameters, not per-row columns of the frames:
            # DuckDB reads a numpy string column value by value.
            keys = [*prefix, key.seed, key.code_version]
            con.execute(
                "INSERT INTO carriers (study, scale, condition, seed, run, code_version, "
                '"row", carrier, urgency0, order_time, pickup_time, delivery_time, robot, '
                "run_end, urgency_end) "
                "SELECT ?, ?, ?, ?, run, ?, "
                '"row", carrier, urgency0, order_time, pickup_time, delivery_time, '
                "CAST(robot AS BIGINT), run_end, CAST(urgency_end AS BIGINT) FROM chunk_carriers",
                keys,
            )
            con.execute(
                "INSERT INTO events SELECT ?, ?, ?, ?, run, ?, "
                '"row", time, kind, CAST(carrier AS BIGINT), CAST(robot AS BIGINT), value '
                "FROM chunk_events",
                keys,
            )
            con.execute("COMMIT")
        except duckdb.ConstraintException as error:
            con.execute("ROLLBACK")
            msg = (
                f"write_chunk: runs {run_ids.tolist()} of {condition} are already stored ({error})"
            )
            raise StoreError(msg) from None
        except duckdb.Error as error:  # a full disk at COMMIT: none of the chunk is stored
            with contextlib.suppress(duckdb.Error):
                con.execute("ROLLBACK")
            raise self._failed(
                f"cannot store runs {run_ids.tolist()} of {condition}", error
            ) from None
        except BaseException:
            # A Ctrl-C raised as COMMIT returns finds no transaction left to roll back.
            with contextlib.suppress(duckdb.TransactionException):
                con.execute("ROLLBACK")
            raise
        finally:
            for view in ("chunk_runs", "chunk_carriers", "chunk_events"):
                con.unregister(view)
        return len(run_ids)

    # -- reading ---------------------------------------------------------------------------

    def stored_runs(self, key: RunKey, condition: str) -> set[int]:
        """The run indices stored for one condition under ``key``."""
        rows = self._con.execute(_STORED_RUNS, [*key.params(), condition]).fetchall()
        return {int(row[0]) for row in rows}

    def missing_runs(self, key: RunKey, condition: str, runs: Iterable[int]) -> list[int]:
        """The runs among ``runs`` not yet stored for ``condition`` under ``key``, sorted."""
        stored = self.stored_runs(key, condition)
        return sorted(set(runs) - stored)

    def count_runs(self) -> int:
        """How many runs the store holds in all (any study, scale and version)."""
        row = self._con.execute("SELECT count(*) FROM runs").fetchone()
        assert row is not None
        return int(row[0])

    def load_log(self, key: RunKey, conditions: Sequence[str], runs: int) -> CarrierLog:
        """Runs ``0 .. runs-1`` of ``conditions`` (in that order) as one ``CarrierLog``.

        The rows come back in the order ``simulate`` produced them, so the
        log is byte-identical (as CSV) to simulating the same runs.
        ``StoreError`` if any of those runs is not stored.
        """
        unit = self._check_complete(key, conditions, runs)
        parts = []
        for condition in conditions:
            rows = self._con.execute(
                self._carrier_rows, [*key.params(), condition, runs]
            ).fetchall()
            parts.append(_carrier_log(rows, unit))
        return CarrierLog.concat(parts)

    def load_events(self, key: RunKey, conditions: Sequence[str], runs: int) -> EventTable:
        """The event tables of runs ``0 .. runs-1`` of ``conditions``, in simulated order."""
        unit = self._check_complete(key, conditions, runs)
        parts = []
        for condition in conditions:
            rows = self._con.execute(_EVENT_ROWS, [*key.params(), condition, runs]).fetchall()
            parts.append(_event_table(rows, unit))
        return EventTable.concat(parts)

    def _check_complete(self, key: RunKey, conditions: Sequence[str], runs: int) -> str | None:
        """Raise unless every run is stored; the runs' one time unit."""
        for condition in conditions:
            missing = self.missing_runs(key, condition, range(runs))
            if missing:
                shown = ", ".join(str(run) for run in missing[:5])
                more = " ..." if len(missing) > 5 else ""
                msg = (
                    f"{key.study}/{key.scale}: {condition} lacks runs {shown}{more} of {runs} "
                    f"(code version {key.code_version}); run the study to compute them"
                )
                raise StoreError(msg)
        units = self._con.execute(_TIME_UNITS, [*key.params(), list(conditions), runs]).fetchall()
        if len(units) != 1:
            msg = f"{key.study}/{key.scale}: stored runs mix time units {sorted(map(str, units))}"
            raise StoreError(msg)
        unit = units[0][0]
        return None if unit is None else str(unit)

    def export(
        self,
        key: RunKey,
        conditions: Sequence[str],
        runs: int,
        folder: str | os.PathLike[str],
        *,
        fmt: str = "csv",
    ) -> tuple[Path, Path]:
        """Write ``carriers.<fmt>`` and ``events.<fmt>`` (``csv`` or ``parquet``) to ``folder``."""
        _check_format(fmt)
        log, events = self.load_log(key, conditions, runs), self.load_events(key, conditions, runs)
        return export_logs(log, events, folder, fmt=fmt)


def _check_format(fmt: str) -> None:
    """Refuse an export format other than ``csv`` and ``parquet``."""
    if fmt not in ("csv", "parquet"):
        msg = f"export: format {fmt!r} is not csv or parquet"
        raise StoreError(msg)


def export_logs(
    log: CarrierLog, events: EventTable, folder: str | os.PathLike[str], *, fmt: str = "csv"
) -> tuple[Path, Path]:
    """Write ``log`` and ``events`` as ``carriers.<fmt>`` and ``events.<fmt>`` to ``folder``.

    What ``ResultsStore.export`` writes, from tables already loaded.
    """
    _check_format(fmt)
    target = Path(folder)
    carriers_path, events_path = target / f"carriers.{fmt}", target / f"events.{fmt}"
    write_event_log(log, carriers_path)
    write_event_table(events, events_path)
    return carriers_path, events_path


def _positions(run: np.ndarray[Any, Any]) -> np.ndarray[Any, Any]:
    """Each row's position within its run (0, 1, ...), rows of a run kept in table order."""
    positions = np.zeros(len(run), dtype=np.int64)
    for value in np.unique(run):
        mask = run == value
        positions[mask] = np.arange(int(mask.sum()), dtype=np.int64)
    return positions


def _floats(values: Sequence[Any]) -> np.ndarray[Any, Any]:
    return np.array([np.nan if value is None else value for value in values], dtype=np.float64)


def _carrier_log(rows: Sequence[tuple[Any, ...]], unit: str | None) -> CarrierLog:
    cols = list(zip(*rows, strict=True)) if rows else [()] * 11
    return CarrierLog(
        condition=np.array(cols[0], dtype=np.str_),
        run=np.array(cols[1], dtype=np.int64),
        seed=np.array(cols[2], dtype=np.int64),
        carrier=np.array(cols[3], dtype=np.int64),
        urgency0=np.array(cols[4], dtype=np.int64),
        order_time=_floats(cols[5]),
        pickup_time=_floats(cols[6]),
        delivery_time=_floats(cols[7]),
        robot=np.array(cols[8], dtype=np.int64),
        run_end=_floats(cols[9]),
        urgency_end=np.array(cols[10], dtype=np.int64),
        time_unit=unit,
    )


def _event_table(rows: Sequence[tuple[Any, ...]], unit: str | None) -> EventTable:
    cols = list(zip(*rows, strict=True)) if rows else [()] * 8
    return EventTable(
        condition=np.array(cols[0], dtype=np.str_),
        seed=np.array(cols[1], dtype=np.int64),
        run=np.array(cols[2], dtype=np.int64),
        time=_floats(cols[3]),
        kind=np.array(cols[4], dtype=np.str_),
        carrier=np.array(cols[5], dtype=np.int64),
        robot=np.array(cols[6], dtype=np.int64),
        value=_floats(cols[7]),
        time_unit=unit,
    )
