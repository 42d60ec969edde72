"""The first ``make demo`` and ``make test`` in a fresh clone: what a new user waits for.

Run: ``.venv/bin/python benchmarks/bench_fresh_clone.py [--test] [--out FILE.json]``.

Clones this checkout's ``HEAD`` (``git clone``) into a temporary folder and runs, in it,
``make demo`` the first time: its own virtual environment, an empty kernel cache (numba's
cache lives beside the sources), the install, the kernel's compilation and the demo. With
``--test``, a second clone runs ``make test`` and then ``make demo``. pip's download cache
is the machine's, as a user's would be; its size is recorded (``pip_cache_mib``; null: pip
could not say where it is, 0: there is none, so pip downloaded every package). Wall
seconds of each command go to ``benchmarks/results/`` with pytest's own times of the
suite's two parts (``parallel_s``, ``serial_s``) and its slowest tests. On Linux each
command's CPU time is recorded too (``cpu_s``: user and system seconds of every process it
started, the kernel's compilation in the background included: this process adopts the
orphans as a child subreaper and reaps them), and what share of the cores it kept busy. The
targets: ``make demo`` under 2 minutes, ``make test`` under 5.
"""

from __future__ import annotations

import argparse
import ctypes
import os
import re
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from _results import ROOT, begin, children_cpu_s

PYTEST_TIME = re.compile(r"=+ .*? in ([0-9.]+)s")
SLOW_LINE = re.compile(r"^([0-9.]+)s (call|setup|teardown) +(\S+)$")


def clone(folder: Path) -> Path:
    """A fresh clone of this checkout's HEAD in ``folder``."""
    target = folder / "swarmtag"
    subprocess.run(["git", "clone", "--quiet", os.fspath(ROOT), os.fspath(target)], check=True)
    return target


PR_SET_CHILD_SUBREAPER = 36
"""Linux's prctl option: orphaned descendants are re-parented to this process, not to init."""


def adopt_orphans() -> bool:
    """Become a child subreaper (Linux), so background processes' CPU time can be counted."""
    if not sys.platform.startswith("linux"):
        return False
    libc = ctypes.CDLL(None, use_errno=True)
    return bool(libc.prctl(PR_SET_CHILD_SUBREAPER, 1, 0, 0, 0) == 0)


def reap_all() -> None:
    """Wait for every remaining descendant (orphans adopted as a subreaper included)."""
    while True:
        try:
            os.waitpid(-1, 0)
        except ChildProcessError:
            return


def make(target: str, where: Path, log: Path) -> tuple[float, float]:
    """Run ``make target`` in ``where`` (output to ``log``): wall and CPU seconds. Fails loudly.

    The CPU seconds count the processes it left running in the background only where
    ``adopt_orphans`` succeeded.
    """
    environment = {k: v for k, v in os.environ.items() if k not in {"VIRTUAL_ENV", "PYTHONPATH"}}
    cpu_before = children_cpu_s()
    started = time.perf_counter()
    with log.open("w", encoding="utf-8") as out:
        done = subprocess.run(
            ["make", target],
            check=False,
            cwd=where,
            stdout=out,
            stderr=subprocess.STDOUT,
            env=environment,
        )
    seconds = time.perf_counter() - started
    reap_all()
    if done.returncode:
        tail = log.read_text(encoding="utf-8", errors="replace")[-3000:]
        sys.exit(f"make {target} failed (exit {done.returncode}) in {where}:\n{tail}")
    return seconds, children_cpu_s() - cpu_before


def pip_cache_mib() -> float | None:
    """The size of pip's download cache, MiB (0: none; None where pip cannot say)."""
    done = subprocess.run(
        [sys.executable, "-m", "pip", "cache", "dir"], capture_output=True, text=True, check=False
    )
    folder = Path(done.stdout.strip())
    if done.returncode:
        return None
    if not folder.is_dir():
        return 0.0  # no cache: pip downloads every package
    size = sum(path.stat().st_size for path in folder.rglob("*") if path.is_file())
    return round(size / 2**20, 1)


def main() -> None:
    """Clone, run, record."""
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--test", action="store_true", help="also make test (about 9 minutes)")
    parser.add_argument("--keep", action="store_true", help="keep the clones and their logs")
    args, record = begin(parser, __file__)
    record.summary["pip_cache_mib"] = pip_cache_mib()
    counted = adopt_orphans()
    cores = os.cpu_count() or 1

    def cpu(seconds: float, cpu_s: float) -> dict[str, float | None]:
        """The row's CPU fields: None where background processes could not be counted."""
        if not counted:
            return {"cpu_s": None, "busy": None}
        return {"cpu_s": round(cpu_s, 1), "busy": round(cpu_s / (seconds * cores), 3)}

    folder = Path(tempfile.mkdtemp(prefix="swarmtag-fresh-"))
    try:
        demo = clone(folder / "demo")
        seconds, cpu_s = make("demo", demo, folder / "demo.log")
        record.row(command="make demo", clone="fresh", seconds=seconds, **cpu(seconds, cpu_s))
        record.summary["first_demo_s"] = seconds
        print(f"first make demo: {seconds:.0f} s (target 120 s), {cpu_s:.0f} s of CPU")
        if args.test:
            tested = clone(folder / "test")
            log = folder / "test.log"
            seconds, cpu_s = make("test", tested, log)
            text = log.read_text(encoding="utf-8", errors="replace")
            parts = [float(found) for found in PYTEST_TIME.findall(text)]
            slowest = [
                {"seconds": float(m.group(1)), "test": m.group(3)}
                for line in text.splitlines()
                if (m := SLOW_LINE.match(line.strip()))
            ]
            record.row(
                command="make test",
                clone="fresh",
                seconds=seconds,
                pytest_parts=parts,
                **cpu(seconds, cpu_s),
            )
            record.summary.update(first_test_s=seconds, slowest=slowest[:30])
            if len(parts) == 2:
                record.summary.update(parallel_s=parts[0], serial_s=parts[1])
            print(
                f"first make test: {seconds:.0f} s (target 300 s), {cpu_s:.0f} s of CPU;"
                f" pytest parts {parts}"
            )
            after, cpu_s = make("demo", tested, folder / "demo-after-test.log")
            record.row(
                command="make demo", clone="after make test", seconds=after, **cpu(after, cpu_s)
            )
            print(f"make demo after it: {after:.0f} s")
    finally:
        if args.keep:
            print(f"kept: {folder}")
        else:
            shutil.rmtree(folder, ignore_errors=True)
    record.save()


if __name__ == "__main__":
    main()
