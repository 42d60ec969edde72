"""``swarmtag study run``: results where it says, resume through the CLI, one-line errors."""

from __future__ import annotations

import json
import subprocess
import sys

import pytest

from swarmtag.cli import main

from .helpers import SMALL_TOML, write_study


def run(capsys, *argv: str) -> tuple[int, str, str]:
    with pytest.raises(SystemExit) as exited:
        main(["study", "run", *argv])
    out, err = capsys.readouterr()
    return int(exited.value.code or 0), out, err


def test_run_prints_where_results_went(tmp_path, capsys):
    study_file = write_study(tmp_path)
    out_dir = tmp_path / "out"
    code, out, err = run(capsys, str(study_file), "--out", str(out_dir), "--quick",
                         "--workers", "1", "--no-progress")  # fmt: skip
    assert (code, err) == (0, "")
    metrics = out_dir / "small" / "default" / "metrics.json"
    assert out.splitlines() == [
        "small: 4 runs computed, 0 reused from the store",
        f"results store: {out_dir / 'results.duckdb'}",
        f"metrics (default): {metrics}",
    ]
    assert [c["runs"] for c in json.loads(metrics.read_text())["conditions"]] == [2, 2]
    code, out, _ = run(capsys, str(study_file), "--out", str(out_dir), "--workers", "2",
                       "--no-progress")  # fmt: skip
    assert code == 0
    assert out.startswith("small: 8 runs computed, 4 reused from the store\n")


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["no-such-study"], "no such shipped study"),
        (["{bad}"], "study.toml: conditions[2]: 'urgency:alpa=3' is not a condition"),
        (["{good}", "--workers", "0"], "--workers"),
        (["{good}", "--out", "{tmp}/missing/out"], "does not exist"),
        ([], "Missing argument"),
        (["{good}", "--workers", "2", "--scheduler", "tcp://127.0.0.1:9"], "workers or scheduler"),
    ],
)
def test_bad_input_is_one_line_and_exit_2(tmp_path, capsys, argv, message):
    bad = SMALL_TOML.replace('"urgency:alpha=0.7"]', '"urgency:alpha=0.7", "urgency:alpa=3"]')
    names = {
        "bad": write_study(tmp_path, bad),
        "good": write_study(tmp_path, SMALL_TOML, "good.toml"),
        "tmp": tmp_path,
    }
    code, out, err = run(capsys, *(arg.format(**names) for arg in argv))
    assert code == 2
    assert out == ""
    assert len(err.strip().splitlines()) == 1
    assert err.startswith("swarmtag: error: ")
    assert message in err


def test_a_store_held_by_another_process_is_refused_in_one_line(tmp_path, capsys):
    study_file = write_study(tmp_path)
    out_dir = tmp_path / "out"
    out_dir.mkdir()
    holder = subprocess.Popen(
        [sys.executable, "-c", HOLD, str(out_dir / "results.duckdb")],
        stdout=subprocess.PIPE,
        stdin=subprocess.PIPE,
    )
    try:
        assert holder.stdout is not None
        assert holder.stdout.readline() == b"ready\n"
        code, _, err = run(capsys, str(study_file), "--out", str(out_dir), "--workers", "1")
    finally:
        holder.communicate(b"done\n", timeout=10)
    assert code == 2
    assert "cannot open the results store" in err
    assert len(err.strip().splitlines()) == 1


HOLD = """
import sys
from swarmtag.experiments import ResultsStore
with ResultsStore(sys.argv[1]):
    print("ready", flush=True)
    sys.stdin.readline()
"""
