"""Compile (or load) the fast kernel's entry points and the bootstrap's compiled loops.

``python -m tests.kernel_warmup ENTRY [ENTRY ...]`` (``batched``, ``split``,
``statistics``): ``tests/conftest.py`` warms all three before any test, so
that every test worker loads machine code instead of compiling it again and
a command-line test never meets the first-compilation note on stderr;
``make`` starts the kernel's as soon as numba is installed (``make demo``:
``batched``; ``make test``: ``batched split``), and ``statistics`` once the
package's core (scipy) is in.

Each entry compiles in a process of its own, side by side. ``batched``
compiles its phase functions first, each cached, then its own top. With
nothing cached, a helper process (``ahead``) compiles the last two phases
(the collisions and the tick's end) at the same time, and ``batched`` loads
them when it gets to them: 77 s -> 53 s on two cores, which is what the
first ``make demo`` waits for. ``split`` shares the phase functions, so it
starts only once they are all cached, loads them, and compiles its own part
(about 23 s): about 40 s of CPU less than compiling both from scratch at
once, which is what the first ``make test`` waits for while pip and mypy
share the cores.

A warm-up of several entries holds a lock in numba's cache folder
(``lock``) while it runs, and one started while another holds it waits for
it, then loads what that one compiled: so ``make test`` starts pytest while
its install's warm-up is still compiling, and the test workers collect
meanwhile; ``--wait`` only waits (``make demo``). The imports that load
numba and swarmtag come after the lock is taken.
"""

from __future__ import annotations

import importlib.util
import os
import subprocess
import sys
import threading
import traceback
from collections.abc import Iterator, Sequence
from contextlib import contextmanager
from pathlib import Path
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from swarmtag.io import CarrierLog

ENTRIES = ("batched", "split", "statistics")
"""The kernel's entry points (``_tick.advance``, which runs on threads, and
``_split.split_ticks``) and the bootstrap's compiled loops (``analysis._compiled``)."""

AHEAD = "ahead"
"""The helper process of a cold ``batched`` warm-up (``warm_ahead``), not an entry of its own."""


LOCK_NAME = "kernel-warmup.lock"
"""The lock's file name in numba's cache folder."""


def lock_path() -> Path:
    """The lock of the cache the kernel is compiled into: ``NUMBA_CACHE_DIR``, else the kernel's own.

    numba caches a module's functions in the ``__pycache__`` beside it
    unless ``NUMBA_CACHE_DIR`` names a folder (``tests/test_kernel_warmup.py``
    uses one of its own): one lock per cache.
    """
    folder = os.environ.get("NUMBA_CACHE_DIR", "")
    if folder:
        path = Path(folder, LOCK_NAME)
    else:
        spec = importlib.util.find_spec("swarmtag")  # finds the package without importing it
        if spec is None or not spec.submodule_search_locations:
            msg = "the kernel warm-up needs swarmtag installed"
            raise RuntimeError(msg)
        path = Path(spec.submodule_search_locations[0], "sim", "fast", "__pycache__", LOCK_NAME)
    path.parent.mkdir(parents=True, exist_ok=True)
    return path


@contextmanager
def lock(note: str = "") -> Iterator[None]:
    """Hold the warm-up lock; if another warm-up holds it, print ``note`` (if any) and wait.

    Without POSIX file locks (Windows), or where the cache folder cannot
    hold the lock's file, there is none: warm-ups started together then
    each compile what is not cached yet.
    """
    if sys.platform == "win32":
        yield
        return
    import fcntl

    try:
        handle = lock_path().open("a")
    except OSError:
        yield
        return
    with handle:
        try:
            fcntl.flock(handle, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            if note:
                print(note, flush=True)
            fcntl.flock(handle, fcntl.LOCK_EX)
        try:
            yield
        finally:
            fcntl.flock(handle, fcntl.LOCK_UN)


def warm(entry: str) -> None:
    """Run two ticks through ``entry``: numba compiles it, or loads it from its cache."""
    from dataclasses import replace

    from swarmtag.analysis import summarize
    from swarmtag.policy import Urgency
    from swarmtag.sim import Scenario, simulate

    if entry == "statistics":
        summarize(_mixed_log(), n_resamples=200, compiled=True)
        return
    scenario = replace(Scenario.default(3, 7), ticks=2)
    if entry == "batched":
        simulate(scenario, Urgency(alpha=0.7), seed=0, runs=1, backend="fast", threads=1)
        return
    from swarmtag.sim.fast import _runner  # numba only where it is installed

    _runner.SPLIT_FROM = 1  # a run of 3 robots on two threads takes the split path
    simulate(scenario, Urgency(alpha=0.7), seed=0, runs=1, backend="fast", threads=2)


def _mixed_log(runs: int = 12, carriers: int = 7) -> CarrierLog:
    """Two conditions of ``runs`` x ``carriers``, about one carrier in forty undelivered.

    Censored carriers, but few enough that the Kaplan-Meier P95 is defined:
    so every compiled loop of a real summary runs, with a real summary's
    argument types (``tests/test_kernel_warmup.py`` checks that none is left).
    """
    import numpy as np

    from swarmtag.io import CarrierLog

    rows = 2 * runs * carriers
    draws = np.random.default_rng(0)
    order = draws.uniform(0, 80, rows)
    pickup = order + draws.uniform(1, 25, rows)
    delivery = pickup + draws.uniform(1, 25, rows)
    delivery[draws.random(rows) < 1 / 40] = np.nan
    pickup[np.isnan(delivery) & (draws.random(rows) < 0.5)] = np.nan
    return CarrierLog(
        condition=np.repeat(["proximity", "urgency:alpha=0.7"], runs * carriers).tolist(),
        run=np.tile(np.repeat(np.arange(runs), carriers), 2),
        seed=np.zeros(rows, dtype=np.int64),
        carrier=np.tile(np.arange(carriers), 2 * runs),
        urgency0=draws.integers(1, 10, rows),
        order_time=order,
        pickup_time=pickup,
        delivery_time=delivery,
        robot=np.where(np.isnan(pickup), -1, 0),
        run_end=np.full(rows, 130.0),
    )


def _start(entry: str) -> subprocess.Popen[str]:
    """``entry`` warmed in a process of its own, its output kept for a failure's message."""
    return subprocess.Popen(
        [sys.executable, "-m", "tests.kernel_warmup", entry],
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        text=True,
    )


def warm_all(entries: Sequence[str]) -> list[str]:
    """Warm ``entries`` side by side (``split`` after ``batched``'s shared code); the failures.

    ``batched`` runs in this process; a numba compile listener starts
    ``split`` as soon as the last phase function the two share is compiled
    and cached, or at once when ``batched`` was cached already (nothing to
    share then). Returns the output of every entry that failed.
    """
    wanted = [entry for entry in ENTRIES if entry in entries]
    started = {entry: _start(entry) for entry in wanted if entry not in ("batched", "split")}
    failed: list[str] = []
    if "batched" in wanted:
        failed += _warm_batched_then_split(started, split="split" in wanted)
    elif "split" in wanted:
        started["split"] = _start("split")
    for entry, process in started.items():
        output = process.communicate()[0]
        if process.returncode:
            failed.append(f"{entry}: {output}")
    return failed


def _warm_batched_then_split(
    started: dict[str, subprocess.Popen[str]], *, split: bool
) -> list[str]:
    """Warm ``batched`` here, its last phases beside it; then ``split``, into ``started``.

    With nothing cached, ``ahead`` compiles ``batched``'s last two phases in
    a process of its own while this one compiles the others, and this one
    then loads them (``warm_ahead``). ``split`` starts once every phase the
    two share is cached: the last this process compiles (``move_robots``)
    and the ahead process's. Returns the output of each of them that failed.
    """
    from numba.core import event

    from swarmtag.sim.fast._motion import move_robots
    from swarmtag.sim.fast._runner import kernel_compiled

    if kernel_compiled():
        if split:
            started["split"] = _start("split")
        return _warm_batched()
    shared = threading.Event()
    ahead = _start(AHEAD)
    outputs: list[str] = []

    def split_once_shared() -> None:
        output = ahead.communicate()[0]
        if ahead.returncode:
            outputs.append(f"{AHEAD}: {output}")
        shared.wait()
        if split:
            started["split"] = _start("split")

    class SharedCompiled(event.Listener):
        """Tells the waiting thread when ``move_robots`` is compiled and cached."""

        def on_start(self, compile_event: event.Event) -> None:
            pass

        def on_end(self, compile_event: event.Event) -> None:
            if compile_event.data["dispatcher"] is move_robots:
                shared.set()

    waiting = threading.Thread(target=split_once_shared)
    waiting.start()
    try:
        with event.install_listener("numba:compile", SharedCompiled()):
            failed = _warm_batched()
    finally:
        shared.set()
        waiting.join()
    return failed + outputs


def _warm_batched() -> list[str]:
    """Warm ``batched`` in this process; its traceback if that failed."""
    try:
        warm("batched")
    except Exception:  # noqa: BLE001 - reported like a failed process's output
        return [f"batched: {traceback.format_exc()}"]
    return []


def ahead_signatures() -> list[tuple[Any, tuple[object, ...]]]:
    """``batched``'s last two phases and the argument types its entry point calls them with.

    A batched run is started and stopped at its call of ``_tick.advance``:
    ``advance`` passes the world, constants and scratch it is given on to
    every phase unchanged, with the run's row and the tick as int64, so
    their types are the dispatcher's own typing of those arguments.
    ``tests/test_kernel_warmup.py`` checks them against the cached kernel.
    """
    from numba import types

    from swarmtag.sim.fast import _runner
    from swarmtag.sim.fast._collide import resolve_run
    from swarmtag.sim.fast._tick import advance, tick_end

    captured: list[object] = []

    class _Captured(Exception):
        """Stops the run at its call of the kernel."""

    def capture(*arguments: object) -> None:
        captured.extend(arguments[-3:])  # w, k, x
        raise _Captured

    _runner.advance = capture
    try:
        warm("batched")
    except _Captured:
        pass
    finally:
        _runner.advance = advance
    w, k, x = (advance.typeof_pyval(value) for value in captured)
    return [(resolve_run, (types.int64, w, k, x)), (tick_end, (types.int64, types.int64, w, k, x))]


def warm_ahead() -> None:
    """Compile (and cache) ``ahead_signatures``: what ``batched`` then loads instead of compiling."""
    for dispatcher, signature in ahead_signatures():
        dispatcher.compile(signature)


WAITING = "make: waiting for the fast kernel's compilation (started during the install)"
"""What ``--wait`` prints when it has to wait."""

KERNEL_PACKAGES = ("numpy", "numba")
"""What the kernel's warm-up imports (``make`` installs them first, then starts it)."""


def kernel_requirements(pyproject: Path) -> list[str]:
    """``KERNEL_PACKAGES``' requirements as ``pyproject`` declares them (core and extras).

    ``make`` installs these first, with the project's own bounds, so that the
    install of the rest, while the kernel compiles, never replaces them.
    """
    import re
    import tomllib

    project = tomllib.loads(pyproject.read_text(encoding="utf-8"))["project"]
    declared = [*project["dependencies"], *project["optional-dependencies"]["fast"]]
    found = [
        requirement
        for requirement in declared
        if (match := re.match(r"[A-Za-z0-9_.-]+", requirement))
        and match.group().lower() in KERNEL_PACKAGES
    ]
    if len(found) != len(KERNEL_PACKAGES):
        msg = f"pyproject.toml declares {found}, not one requirement each of {KERNEL_PACKAGES}"
        raise ValueError(msg)
    return found


if __name__ == "__main__":
    arguments = sys.argv[1:]
    if arguments == ["--wait"]:
        with lock(WAITING):
            sys.exit(0)
    if arguments == [AHEAD]:
        warm_ahead()
        sys.exit(0)
    if arguments == ["--requirements"]:
        print(*kernel_requirements(Path(__file__).resolve().parent.parent / "pyproject.toml"))
        sys.exit(0)
    if not arguments or any(entry not in ENTRIES for entry in arguments):
        entries = "|".join(ENTRIES)
        sys.exit(f"usage: python -m tests.kernel_warmup {{--wait|--requirements|{entries} ...}}")
    if len(arguments) == 1 and arguments[0] != "batched":
        warm(arguments[0])  # one entry: a warm-up's own process, or a cache of its own
    else:
        with lock():
            problems = warm_all(arguments)
        if problems:
            sys.exit("\n".join(problems))
