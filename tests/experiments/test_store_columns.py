"""The results store keeps run_end and urgency_end, and opens stores made before they existed."""

from __future__ import annotations

import duckdb
import numpy as np

from swarmtag.experiments import ResultsStore, RunKey
from swarmtag.io import CarrierLog, EventTable, format_csv

KEY = RunKey(study="s", scale="default", seed=3, code_version="v1")
NAN = float("nan")

# The store's schema before the optional carrier columns (swarmtag 0.1.0, first release).
OLD_SCHEMA = """
CREATE TABLE runs (
    study VARCHAR NOT NULL, scale VARCHAR NOT NULL, condition VARCHAR NOT NULL,
    seed BIGINT NOT NULL, run BIGINT NOT NULL, code_version VARCHAR NOT NULL,
    carrier_rows BIGINT NOT NULL, event_rows BIGINT NOT NULL, time_unit VARCHAR,
    PRIMARY KEY (study, scale, condition, seed, run, code_version)
);
CREATE TABLE carriers (
    study VARCHAR NOT NULL, scale VARCHAR NOT NULL, condition VARCHAR NOT NULL,
    seed BIGINT NOT NULL, run BIGINT NOT NULL, code_version VARCHAR NOT NULL,
    "row" BIGINT NOT NULL, carrier BIGINT NOT NULL, urgency0 BIGINT NOT NULL,
    order_time DOUBLE NOT NULL, pickup_time DOUBLE, delivery_time DOUBLE, robot BIGINT
);
CREATE TABLE events (
    study VARCHAR NOT NULL, scale VARCHAR NOT NULL, condition VARCHAR NOT NULL,
    seed BIGINT NOT NULL, run BIGINT NOT NULL, code_version VARCHAR NOT NULL,
    "row" BIGINT NOT NULL, time DOUBLE NOT NULL, kind VARCHAR NOT NULL,
    carrier BIGINT, robot BIGINT, value DOUBLE
);
INSERT INTO runs VALUES ('s', 'default', 'proximity', 3, 0, 'v1', 2, 0, 'tick');
INSERT INTO carriers VALUES
    ('s', 'default', 'proximity', 3, 0, 'v1', 0, 1, 9, -5.0, 2.0, 8.0, 0),
    ('s', 'default', 'proximity', 3, 0, 'v1', 1, 2, 3, -1.0, NULL, NULL, NULL);
"""


def _log(run: int, *, ends: bool) -> CarrierLog:
    return CarrierLog(
        condition=["proximity"] * 2,
        run=[run, run],
        seed=[3, 3],
        carrier=[1, 2],
        urgency0=[9, 3],
        order_time=[-5.0, -1.0],
        pickup_time=[2.0, NAN],
        delivery_time=[8.0, NAN],
        robot=[0, -1],
        time_unit="tick",
        run_end=[100.0, 100.0] if ends else None,
        urgency_end=[9, 6] if ends else None,
    )


def _no_events() -> EventTable:
    empty: list[int] = []
    return EventTable(
        condition=np.array([], dtype=str),
        seed=empty,
        run=empty,
        time=np.array([]),
        kind=np.array([], dtype=str),
        carrier=empty,
        robot=empty,
        value=np.array([]),
        time_unit="tick",
    )


def test_the_optional_columns_round_trip(tmp_path):
    with ResultsStore(tmp_path / "results.duckdb") as store:
        store.write_chunk(KEY, _log(0, ends=True), _no_events())
        store.write_chunk(KEY, _log(1, ends=False), _no_events())
        loaded = store.load_log(KEY, ["proximity"], 2)
    expected = CarrierLog.concat([_log(0, ends=True), _log(1, ends=False)])
    assert loaded == expected
    assert loaded.run_end.tolist()[:2] == [100.0, 100.0]
    assert np.isnan(loaded.run_end[2:]).all()
    assert loaded.urgency_end.tolist() == [9, 6, -1, -1]
    assert format_csv(loaded) == format_csv(expected)


def test_a_store_from_before_the_columns_opens_read_only_and_for_writing(tmp_path):
    path = tmp_path / "results.duckdb"
    with duckdb.connect(str(path)) as con:
        con.execute(OLD_SCHEMA)
    old = _log(0, ends=False)
    with ResultsStore(path, read_only=True) as store:  # cannot change the file: reads NULLs
        assert store.load_log(KEY, ["proximity"], 1) == old
    with ResultsStore(path) as store:  # gains the columns, keeps the rows
        store.write_chunk(KEY, _log(1, ends=True), _no_events())
        both = store.load_log(KEY, ["proximity"], 2)
    assert both == CarrierLog.concat([old, _log(1, ends=True)])
    with duckdb.connect(str(path), read_only=True) as con:
        columns = [row[0] for row in con.execute("DESCRIBE carriers").fetchall()]
    assert columns[-2:] == ["run_end", "urgency_end"]
