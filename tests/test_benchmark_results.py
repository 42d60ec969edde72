"""The benchmark scripts record their results through ``benchmarks/_results.py``.

docs/performance.md promises that every script in ``benchmarks/`` writes a JSON
file to ``benchmarks/results/`` with the machine, the commit and the arguments.
"""

import argparse
import ast
import importlib.util
import json
from pathlib import Path

import numpy as np
import pytest

BENCHMARKS = Path(__file__).resolve().parent.parent / "benchmarks"
SCRIPTS = sorted(p for p in BENCHMARKS.glob("*.py") if not p.name.startswith("_"))
STORED = sorted((BENCHMARKS / "results").glob("*.json"))


@pytest.fixture(scope="module")
def helper():
    spec = importlib.util.spec_from_file_location("benchmark_results", BENCHMARKS / "_results.py")
    assert spec is not None
    assert spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_there_are_scripts_and_stored_results():
    assert len(SCRIPTS) >= 8
    assert STORED, "benchmarks/results/ holds no results file"


@pytest.mark.parametrize("script", SCRIPTS, ids=lambda p: p.name)
def test_every_script_records_its_results_through_the_helper(script):
    tree = ast.parse(script.read_text(encoding="utf-8"))
    imported = {
        alias.name
        for node in ast.walk(tree)
        if isinstance(node, ast.ImportFrom) and node.module == "_results"
        for alias in node.names
    }
    assert "begin" in imported
    called = {
        node.func.attr if isinstance(node.func, ast.Attribute) else getattr(node.func, "id", "")
        for node in ast.walk(tree)
        if isinstance(node, ast.Call)
    }
    assert {"begin", "save"} <= called


def test_a_results_file_holds_the_machine_the_commit_and_the_arguments(helper, tmp_path, capsys):
    out = tmp_path / "bench.json"
    args = argparse.Namespace(runs=3, quick=False, out=out)
    record = helper.Record("benchmarks/bench_example.py", args, out=out)
    record.row(case="a", rate=float("nan"), value=np.float64(1.5), band=(np.float64(1.25), 2.5))
    record.summary["slope"] = np.float64(0.97)
    assert record.save() == out
    assert "results:" in capsys.readouterr().out

    data = json.loads(out.read_text(encoding="utf-8"))
    assert data["benchmark"] == "bench_example"
    assert data["arguments"] == {"runs": 3, "quick": False, "out": str(out)}
    assert data["rows"] == [{"case": "a", "rate": None, "value": 1.5, "band": [1.25, 2.5]}]
    assert data["summary"] == {"slope": 0.97}
    machine = data["machine"]
    assert {"cpu", "cores", "memory_gib", "python", "numpy", "numba", "probe_s"} <= set(machine)
    assert machine["numpy"] == np.__version__
    assert data["commit"] is None or len(data["commit"]) == 40
    assert data["date"].endswith("+00:00")
    assert data["command"].startswith("python benchmarks/")


def test_by_default_each_run_is_a_new_file_in_benchmarks_results(helper):
    record = helper.Record("benchmarks/bench_example.py", argparse.Namespace(quick=True))
    path = record.default_path()
    assert path.parent == BENCHMARKS / "results"
    assert path.name.startswith("bench_example-quick-")
    assert path.suffix == ".json"


@pytest.mark.parametrize("path", STORED, ids=lambda p: p.name)
def test_stored_results_name_their_script_machine_and_commit(path):
    data = json.loads(path.read_text(encoding="utf-8"))
    assert {"benchmark", "command", "arguments", "date", "commit", "machine", "rows"} <= set(data)
    assert (BENCHMARKS / f"{data['benchmark']}.py").is_file()
    assert data["command"].startswith(f"python benchmarks/{data['benchmark']}.py")
    assert data["rows"]
