"""Where the test suite's CPU time goes: each module's tests, and the reference backend's runs.

Run: ``.venv/bin/python benchmarks/bench_suite.py [--workers N] [--out FILE.json] [PATH ...]``
(the kernel cache warm, as after a first ``make test``; about 4.5 minutes on two cores).

Runs the parallel part of ``make test`` (``pytest -n N --dist worksteal -m "not serial"``,
or only the given test paths) with ``_suite_plugin.py`` loaded in every worker, which
times each test: its wall seconds, the CPU seconds of its worker and of the processes the
test started and waited for, and the seconds spent in the reference backend's
``run_batch``. Records the whole run's wall and CPU time (every process pytest started),
how busy it kept the cores, and per test module: tests, wall, CPU and reference seconds,
the costliest first (``benchmarks/results/``, ``_results.py``). What it says: how much of
the suite is CPU work, and how much of that is the reference backend's runs, against the
5 minutes of ``make test`` on two cores.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from dataclasses import asdict, dataclass
from pathlib import Path

from _results import ROOT, begin, children_cpu_s

HERE = Path(__file__).resolve().parent
TOP = 15
"""Modules printed (all are recorded)."""


def run_suite(workers: int, paths: list[str], folder: Path) -> tuple[float, float, int]:
    """The parallel part with the plugin: wall seconds, CPU seconds, pytest's exit status."""
    environment = {
        **os.environ,
        "PYTHONPATH": os.pathsep.join(filter(None, [str(HERE), os.environ.get("PYTHONPATH")])),
        "PYTHONDONTWRITEBYTECODE": "",  # as make test: pytest keeps its rewritten modules
        "SWARMTAG_SUITE_PROFILE": str(folder),
    }
    command = [
        sys.executable,
        "-m",
        "pytest",
        "-q",
        f"--numprocesses={workers}",
        "--dist=worksteal",
        "-m",
        "not serial",
        "-p",
        "_suite_plugin",
        *paths,
    ]
    cpu = children_cpu_s()
    began = time.perf_counter()
    done = subprocess.run(command, cwd=ROOT, env=environment, check=False)
    return time.perf_counter() - began, children_cpu_s() - cpu, done.returncode


@dataclass
class Module:
    """One test module's tests and their summed seconds."""

    module: str
    tests: int = 0
    wall_s: float = 0.0
    cpu_s: float = 0.0
    reference_s: float = 0.0


def by_module(rows: list[dict[str, str | float]]) -> list[Module]:
    """The tests' rows summed per module, the costliest in CPU first."""
    sums: dict[str, Module] = {}
    for row in rows:
        name = str(row["test"]).split("::", 1)[0]
        module = sums.setdefault(name, Module(name))
        module.tests += 1
        module.wall_s += float(row["wall_s"])
        module.cpu_s += float(row["cpu_s"])
        module.reference_s += float(row["reference_s"])
    return sorted(sums.values(), key=lambda module: -module.cpu_s)


def main() -> None:
    """Run, sum, print, record."""
    parser = argparse.ArgumentParser(description=__doc__)
    cores = (
        len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count() or 1
    )
    parser.add_argument("--workers", type=int, default=cores, help="pytest workers")
    parser.add_argument("paths", nargs="*", help="test paths (default: the whole suite)")
    args, record = begin(parser, __file__)
    with tempfile.TemporaryDirectory(prefix="swarmtag-suite-") as folder:
        wall, cpu, status = run_suite(args.workers, args.paths, Path(folder))
        rows: list[dict[str, str | float]] = []
        for path in sorted(Path(folder).glob("*.json")):
            rows += json.loads(path.read_text(encoding="utf-8"))
    if status:
        sys.exit(f"pytest failed (exit {status}): no figures recorded")
    modules = by_module(rows)
    tests_cpu = sum(module.cpu_s for module in modules)
    reference = sum(module.reference_s for module in modules)
    busy = cpu / (wall * cores)
    record.summary.update(
        tests=len(rows),
        wall_s=wall,
        cpu_s=cpu,
        busy=busy,
        tests_cpu_s=tests_cpu,
        reference_s=reference,
    )
    for module in modules:
        record.row(**asdict(module))
    print(
        f"{len(rows)} tests: {wall:.0f} s wall, {cpu:.0f} s CPU ({busy:.0%} of {cores} cores);"
        f" the tests' own {tests_cpu:.0f} s of CPU, {reference:.0f} s in reference runs"
    )
    print(f"{'module':<60} {'tests':>5} {'CPU s':>7} {'reference s':>11}")
    for module in modules[:TOP]:
        print(
            f"{module.module:<60} {module.tests:>5} {module.cpu_s:>7.1f}"
            f" {module.reference_s:>11.1f}"
        )
    record.save()


if __name__ == "__main__":
    main()
