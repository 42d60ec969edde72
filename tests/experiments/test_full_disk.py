"""The results store on a full disk: one line, exit 2, and the same command resumes afterwards.

A real tmpfs fills as ``study run`` commits its second chunk (root only;
skipped elsewhere); after the space is freed the same command finishes, and
the store then holds exactly what an uninterrupted run stores. DuckDB's
refusal at COMMIT is also injected, which needs no root.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest

from swarmtag.cli import main
from swarmtag.errors import StoreError
from swarmtag.experiments import ResultsStore, study_key
from tests.full_disk import fill, free, tmpfs

from .helpers import SMALL_TOML, small_study, write_study
from .test_store import simulated

duckdb = pytest.importorskip("duckdb")

ARGS = ["--workers", "1", "--backend", "reference", "--no-progress"]


def run(capsys: pytest.CaptureFixture[str], argv: list[str]) -> tuple[int, str, str]:
    with pytest.raises(SystemExit) as exited:
        main(argv)
    out, err = capsys.readouterr()
    return int(exited.value.code or 0), out, err


def content(store: Path) -> dict[str, list[tuple[Any, ...]]]:
    """Every row of every table of a store, sorted."""
    con = duckdb.connect(str(store), read_only=True)
    try:
        return {
            table: sorted(con.execute(f"SELECT * FROM {table}").fetchall(), key=repr)
            for table in ("runs", "carriers", "events")
        }
    finally:
        con.close()


def test_a_disk_that_fills_during_study_run_is_one_line_and_the_run_resumes(
    tmp_path, capsys, monkeypatch
):
    study = write_study(tmp_path, SMALL_TOML)
    reference = tmp_path / "reference"
    assert run(capsys, ["study", "run", str(study), "--out", str(reference), *ARGS])[0] == 0

    with tmpfs(tmp_path / "device", "8m") as device:
        out = device / "out"
        original = ResultsStore.write_chunk
        calls = []

        def fill_then_write(self: ResultsStore, *args: Any) -> int:
            calls.append(1)
            if len(calls) == 2:  # the first chunk is stored: the disk fills under the second
                fill(device)
            return original(self, *args)

        monkeypatch.setattr(ResultsStore, "write_chunk", fill_then_write)
        code, _, err = run(capsys, ["study", "run", str(study), "--out", str(out), *ARGS])
        store = out / "results.duckdb"
        assert code == 2, err
        assert "Traceback" not in err
        assert err == (
            f"swarmtag: error: no space left on device while writing {store}; "
            "the runs stored before are kept (run again to resume)\n"
        )
        assert not (out / "small" / "default").exists()  # no metrics, no half-written folder

        monkeypatch.undo()
        free(device)
        code, printed, err = run(capsys, ["study", "run", str(study), "--out", str(out), *ARGS])
        assert (code, err) == (0, "")
        assert "2 reused from the store" in printed
        assert content(store) == content(reference / "results.duckdb")
        metrics = (out / "small" / "default" / "metrics.json").read_bytes()
        assert metrics == (reference / "small" / "default" / "metrics.json").read_bytes()


class _RefusingCommit:
    """A DuckDB connection whose COMMIT fails as DuckDB's does on a full disk."""

    def __init__(self, con: Any, path: Path) -> None:
        self._con = con
        self._path = path

    def execute(self, sql: str, *args: Any) -> Any:
        if sql == "COMMIT":
            msg = (
                f'TransactionContext Error: Failed to commit: Could not write file "{self._path}'
                '.wal": No space left on device'
            )
            raise duckdb.TransactionException(msg)
        return self._con.execute(sql, *args)

    def __getattr__(self, name: str) -> Any:
        return getattr(self._con, name)


def test_a_refused_commit_is_one_line_and_stores_none_of_the_chunk(tmp_path):
    study = small_study()
    key = study_key(study, "default")
    path = tmp_path / "results.duckdb"
    carriers, events = simulated("proximity", 2)
    with ResultsStore(path) as store:
        store.write_chunk(key, carriers, events)
        real = store._con
        store._con = _RefusingCommit(real, path)
        later, later_events = simulated("proximity", 2, offset=2)
        with pytest.raises(StoreError) as refused:
            store.write_chunk(key, later, later_events)
        store._con = real
        assert str(refused.value) == (
            f"no space left on device while writing {path}; "
            "the runs stored before are kept (run again to resume)"
        )
        assert store.stored_runs(key, "proximity") == {0, 1}
        store.write_chunk(key, later, later_events)  # the store still takes the chunk afterwards
        assert store.stored_runs(key, "proximity") == {0, 1, 2, 3}


def test_another_refused_commit_is_one_line_in_duckdb_s_words(tmp_path):
    key = study_key(small_study(), "default")
    path = tmp_path / "results.duckdb"
    carriers, events = simulated("proximity", 2)
    with ResultsStore(path) as store:
        real = store._con

        class Refusing(_RefusingCommit):
            def execute(self, sql: str, *args: Any) -> Any:
                if sql == "COMMIT":
                    raise duckdb.TransactionException("Failed to commit:\nsomething else")
                return real.execute(sql, *args)

        store._con = Refusing(real, path)
        with pytest.raises(StoreError) as refused:
            store.write_chunk(key, carriers, events)
        store._con = real
        assert str(refused.value) == (
            f"{path}: cannot store runs [0, 1] of proximity (Failed to commit: something else)"
        )
        assert store.stored_runs(key, "proximity") == set()
