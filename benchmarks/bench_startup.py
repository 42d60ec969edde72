"""What starting a command costs: ``swarmtag --help``, ``import swarmtag`` and a one-run simulate.

Run: ``.venv/bin/python benchmarks/bench_startup.py [--repeat K] [--before REV] [--out FILE.json]``.

- Whole commands in fresh processes, run alternately ``--repeat`` times: ``python -c
  "import numpy"`` (the yardstick of the target), ``python -c "import swarmtag"``,
  ``swarmtag --help`` and ``swarmtag simulate --runs 1`` (the default scenario and
  conditions, statistics included; the fast kernel loaded from its cache).
- With ``--before REV``, ``import swarmtag`` and ``swarmtag --help`` also from the sources
  of git revision REV (``git archive``), side by side.
- Once per command, ``python -X importtime``: the modules it imports first-hand, the
  costliest first, with their cumulative microseconds (the table of docs/performance.md);
  apart, those imported by the processes it forks (``swarmtag._beside``: scipy.stats for
  the Mann-Whitney tests), whose lines go to a file of their own.

Medians of wall time go to ``benchmarks/results/`` (``_results.py``). The target:
``swarmtag --help`` within 3x ``import numpy`` (``summary.help_over_numpy``).
"""

from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
import tarfile
import tempfile
import time
from io import BytesIO
from pathlib import Path

from _results import ROOT, begin

PYTHON = sys.executable
SWARMTAG = [PYTHON, "-c", "from swarmtag.cli import main; main()"]
COMMANDS: dict[str, list[str]] = {
    "import numpy": [PYTHON, "-c", "import numpy"],
    "import swarmtag": [PYTHON, "-c", "import swarmtag"],
    "swarmtag --help": [*SWARMTAG, "--help"],
    "swarmtag simulate --runs 1": [*SWARMTAG, "simulate", "--runs", "1"],
}
BEFORE = ("import swarmtag", "swarmtag --help")
"""The commands also timed on the sources of ``--before`` (no kernel to compile there)."""
TOP = 10
"""First-hand imports listed per command."""


def wall(argv: list[str], env: dict[str, str] | None = None) -> float:
    """Seconds of one whole command in a fresh process (its output thrown away)."""
    start = time.perf_counter()
    subprocess.run(argv, check=True, capture_output=True, env=env, cwd=tempfile.gettempdir())
    return time.perf_counter() - start


FORKED_STDERR = """
import os
def _apart(path={path!r}):
    os.dup2(os.open(path, os.O_WRONLY | os.O_CREAT | os.O_APPEND), 2)
os.register_at_fork(after_in_child=_apart)
"""
"""Put before a ``-c`` command: the processes it forks write their stderr to ``path``."""


def first_hand(argv: list[str]) -> tuple[list[tuple[str, int]], list[tuple[str, int]]]:
    """The modules ``argv`` imports directly (not through another), by cumulative microseconds;
    then those its forked processes import directly (``-c`` commands only, else none)."""
    with tempfile.TemporaryDirectory() as scratch:
        forked = Path(scratch) / "forked.txt"
        forked.touch()
        command = list(argv)
        if command[1] == "-c":
            command[2] = FORKED_STDERR.format(path=str(forked)) + command[2]
        done = subprocess.run(
            [command[0], "-X", "importtime", *command[1:]],
            check=True,
            capture_output=True,
            text=True,
            cwd=tempfile.gettempdir(),
        )
        return _depth_zero(done.stderr), _depth_zero(forked.read_text())


def _depth_zero(stderr: str) -> list[tuple[str, int]]:
    """The depth-0 modules of ``-X importtime`` lines, the costliest first."""
    found: list[tuple[str, int]] = []
    for line in stderr.splitlines():
        parts = line.split("|")
        if not line.startswith("import time:") or len(parts) != 3 or not parts[1].strip().isdigit():
            continue
        name = parts[2]
        if len(name) - len(name.lstrip()) == 1:  # depth 0: imported by the command itself
            found.append((name.strip(), int(parts[1])))
    return sorted(found, key=lambda item: -item[1])


def sources_of(revision: str, into: Path) -> dict[str, str]:
    """An environment importing swarmtag from ``revision``'s sources, extracted into ``into``."""
    archive = subprocess.run(
        ["git", "archive", "--format=tar", revision, "src"],
        cwd=ROOT,
        check=True,
        capture_output=True,
    ).stdout
    with tarfile.open(fileobj=BytesIO(archive)) as tar:
        tar.extractall(into, filter="data")
    return {**os.environ, "PYTHONPATH": str(into / "src")}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--repeat", type=int, default=7, help="runs of each command (default 7)")
    parser.add_argument("--before", default="none", help="git revision to compare with, or none")
    args, record = begin(parser, __file__)
    with tempfile.TemporaryDirectory() as scratch:
        cases: list[tuple[str, list[str], dict[str, str] | None]] = [
            (name, argv, None) for name, argv in COMMANDS.items()
        ]
        if args.before != "none":
            env = sources_of(args.before, Path(scratch))
            cases += [(f"{name} @ {args.before}", COMMANDS[name], env) for name in BEFORE]
        wall(COMMANDS["swarmtag simulate --runs 1"])  # the kernel's cache and the page cache warm
        times: dict[str, list[float]] = {name: [] for name, _, _ in cases}
        for _ in range(args.repeat):
            for name, argv, env in cases:
                times[name].append(wall(argv, env))
    medians = {name: statistics.median(values) for name, values in times.items()}
    for name, argv in COMMANDS.items():
        imports, beside = first_hand(argv)
        record.row(
            command=name,
            seconds=medians[name],
            imports=[
                {"module": module, "microseconds": micros} for module, micros in imports[:TOP]
            ],
            imports_beside=[
                {"module": module, "microseconds": micros} for module, micros in beside[:TOP]
            ],
        )
        listed = ", ".join(f"{module} {micros / 1e3:.0f} ms" for module, micros in imports[:5])
        print(f"{name:<28} {medians[name]:6.3f} s   {listed}")
        if beside:
            listed = ", ".join(f"{module} {micros / 1e3:.0f} ms" for module, micros in beside[:3])
            print(f"{'':<28} {'':>8}     in processes it forked: {listed}")
    for name, seconds in medians.items():
        if "@" in name:
            record.row(command=name, seconds=seconds)
            print(f"{name:<28} {seconds:6.3f} s")
    record.summary["help_over_numpy"] = medians["swarmtag --help"] / medians["import numpy"]
    print(f"swarmtag --help / import numpy: {record.summary['help_over_numpy']:.2f}x (target: 3x)")
    record.save()


if __name__ == "__main__":
    main()
