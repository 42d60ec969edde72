"""Benchmark results as JSON files in ``benchmarks/results/``, with the machine that made them.

Every script in ``benchmarks/`` records what it measured through this module, so the
history of the figures lives in these files and in git, not in prose::

    parser = argparse.ArgumentParser(description=__doc__)
    args, record = begin(parser, __file__)            # adds --out, prints the machine
    record.row(case="3x7", seconds=0.61, rate=9.6e6)   # one per measured row
    record.summary["slope"] = 0.97                     # single figures of the run
    record.save()

A file holds ``benchmark`` (the script's name), ``command`` (the command line as
run), ``arguments`` (every parsed option, defaults included), ``date`` (UTC),
``commit`` and ``dirty`` (the git commit of the working tree, and whether tracked
files differed from it), ``swarmtag`` (the package version), ``machine`` (CPU model,
logical cores usable and present, memory, operating system, Python, numpy and numba
versions, ``SWARMTAG_THREADS``, the load average, and ``probe_s``: the seconds of a
plain Python loop of 10^7 additions when the script started, which tells a slow phase of
a shared machine from a slow program), ``seconds`` (the script's wall time), ``summary`` and
``rows``. The default path is ``benchmarks/results/<script>[-quick]-<UTC date and
time>.json``; ``--out`` chooses another. NaN and infinities are written as ``null``.
"""

from __future__ import annotations

import argparse
import datetime as dt
import json
import math
import os
import platform
import resource
import subprocess
import sys
import time
from importlib import metadata
from pathlib import Path
from typing import Any

import numpy as np

RESULTS = Path(__file__).resolve().parent / "results"
"""Where results go unless ``--out`` says otherwise."""
ROOT = RESULTS.parent.parent
PROBE = 10_000_000
"""Additions in the plain Python loop that says how fast the machine runs right now."""


def add_out_option(parser: argparse.ArgumentParser, flag: str = "--out") -> None:
    """Add the option naming the results file (default: a new file in ``RESULTS``)."""
    parser.add_argument(
        flag,
        type=Path,
        default=None,
        metavar="FILE.json",
        help=f"results file (default: benchmarks/results/{Path(sys.argv[0]).stem}-<UTC time>.json)",
    )


def _cpu_model() -> str:
    """The processor's model name (Linux: /proc/cpuinfo), else what ``platform`` knows."""
    try:
        for line in Path("/proc/cpuinfo").read_text(encoding="utf-8").splitlines():
            if line.startswith("model name"):
                return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or platform.machine()


def _memory_gib() -> float | None:
    """Total memory in GiB (Linux: /proc/meminfo), or None where it cannot be read."""
    try:
        for line in Path("/proc/meminfo").read_text(encoding="utf-8").splitlines():
            if line.startswith("MemTotal:"):
                return round(int(line.split()[1]) / 2**20, 1)
    except (OSError, ValueError, IndexError):
        pass
    return None


def _version(package: str) -> str | None:
    try:
        return metadata.version(package)
    except metadata.PackageNotFoundError:
        return None


def machine() -> dict[str, Any]:
    """The facts of this machine and environment that a benchmark's figures depend on."""
    usable = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else None
    load = [round(x, 2) for x in os.getloadavg()] if hasattr(os, "getloadavg") else None
    return {
        "cpu": _cpu_model(),
        "cores": usable or os.cpu_count(),
        "cores_present": os.cpu_count(),
        "memory_gib": _memory_gib(),
        "system": platform.platform(),
        "python": platform.python_version(),
        "numpy": np.__version__,
        "numba": _version("numba"),
        "threads": os.environ.get("SWARMTAG_THREADS"),
        "load_average": load,
    }


def children_cpu_s() -> float:
    """User and system seconds of this process's waited-for child processes so far."""
    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    return usage.ru_utime + usage.ru_stime


def probe_seconds() -> float:
    """Seconds of a plain Python loop of ``PROBE`` additions at module level.

    Globals in a dict, as ``python -c`` runs it: about 0.75 s on a normal-speed
    phase of the two-core VM of docs/performance.md. A shared virtual machine's
    speed can move by a factor of two within an hour; this says how fast it ran.
    """
    loop = compile(f"total = 0\nfor i in range({PROBE}):\n    total += i\n", "probe", "exec")
    start = time.perf_counter()
    exec(loop, {})  # a fixed loop at module level
    return time.perf_counter() - start


def _git(*arguments: str) -> str | None:
    try:
        done = subprocess.run(
            ["git", *arguments], cwd=ROOT, capture_output=True, text=True, check=True, timeout=30
        )
    except (OSError, subprocess.SubprocessError):
        return None
    return done.stdout.strip()


def _plain(value: object) -> object:
    """``value`` as JSON holds it: floats to 6 significant digits, NaN as None, paths as text."""
    if isinstance(value, dict):
        return {str(key): _plain(item) for key, item in value.items()}
    if isinstance(value, list | tuple):
        return [_plain(item) for item in value]
    if isinstance(value, np.generic):
        value = value.item()
    if isinstance(value, float):
        return float(f"{value:.6g}") if math.isfinite(value) else None
    if isinstance(value, Path):
        return os.fspath(value)
    return value


class Record:
    """The results of one run of a benchmark script, written by ``save`` (to ``out``)."""

    def __init__(self, script: str, args: argparse.Namespace, out: Path | None = None) -> None:
        self.name = Path(script).stem
        self.out = out
        self.arguments = dict(vars(args))
        self.started = time.perf_counter()
        self.date = dt.datetime.now(dt.UTC)
        self.machine = machine()
        self.machine["probe_s"] = round(probe_seconds(), 3)
        self.rows: list[dict[str, Any]] = []
        self.summary: dict[str, Any] = {}

    def machine_line(self) -> str:
        """One line naming the machine, for the top of a script's printout."""
        m = self.machine
        return (
            f"{m['cpu']}, {m['cores']} cores, {m['memory_gib']} GiB; Python {m['python']}, "
            f"numpy {m['numpy']}, numba {m['numba'] or 'not installed'}"
        )

    def row(self, **fields: object) -> None:
        """Add one measured row (any JSON-able fields)."""
        self.rows.append(fields)

    def default_path(self) -> Path:
        quick = "-quick" if self.arguments.get("quick") else ""
        return RESULTS / f"{self.name}{quick}-{self.date:%Y-%m-%dT%H%M%SZ}.json"

    def save(self, path: Path | None = None) -> Path:
        """Write the results file (``path``, else ``out``, else the default) and say where."""
        path = path or self.out or self.default_path()
        status = _git("status", "--porcelain", "--untracked-files=no")
        document = {
            "benchmark": self.name,
            "command": " ".join(["python", f"benchmarks/{Path(sys.argv[0]).name}", *sys.argv[1:]]),
            "arguments": self.arguments,
            "date": self.date.isoformat(timespec="seconds"),
            "commit": _git("rev-parse", "HEAD"),
            "dirty": None if status is None else bool(status),
            "swarmtag": _version("swarmtag"),
            "machine": self.machine,
            "seconds": round(time.perf_counter() - self.started, 3),
            "summary": self.summary,
            "rows": self.rows,
        }
        path.parent.mkdir(parents=True, exist_ok=True)
        text = json.dumps(_plain(document), indent=1, allow_nan=False) + "\n"
        path.write_text(text, encoding="utf-8")
        shown = path.resolve()
        print(f"results: {shown.relative_to(ROOT) if shown.is_relative_to(ROOT) else path}")
        return path


def begin(
    parser: argparse.ArgumentParser, script: str, flag: str = "--out"
) -> tuple[argparse.Namespace, Record]:
    """Add the results option, parse the command line, start the record, print the machine."""
    add_out_option(parser, flag)
    args = parser.parse_args()
    record = Record(script, args, out=getattr(args, flag.lstrip("-").replace("-", "_")))
    print(record.machine_line())
    return args, record
