"""A pytest plugin for ``bench_suite.py``: each test's wall and CPU time, and its reference runs.

Loaded in every test process (``-p _suite_plugin``, this folder on ``PYTHONPATH``). For
each test (set-up, call and tear-down): wall seconds, CPU seconds of the test process and of
the child processes it waited for, and the seconds spent in the reference backend's
``run_batch`` (timed by wrapping it where the package binds it: the outermost call counts).
Each process writes its rows as JSON into the folder named by ``SWARMTAG_SUITE_PROFILE``.
"""

from __future__ import annotations

import json
import os
import resource
import sys
import time
from collections.abc import Callable, Generator
from pathlib import Path
from typing import Any

import pytest

OUT_ENV = "SWARMTAG_SUITE_PROFILE"
"""The environment variable naming the folder the rows go to."""


class _Reference:
    """Seconds in the reference backend's outermost ``run_batch`` calls so far."""

    seconds = 0.0
    depth = 0


_rows: list[dict[str, object]] = []


def _cpu_s() -> float:
    """CPU seconds of this process and of its waited-for children so far."""
    children = resource.getrusage(resource.RUSAGE_CHILDREN)
    return time.process_time() + children.ru_utime + children.ru_stime


def _time_reference_runs() -> None:
    """Wrap ``swarmtag.sim.runner.run_batch`` wherever a loaded module binds it."""
    from swarmtag.sim import runner  # noqa: PLC0415 - after pytest has set up sys.path

    original: Callable[..., Any] = runner.run_batch

    def timed(*args: Any, **kwargs: Any) -> Any:
        if _Reference.depth:
            return original(*args, **kwargs)
        _Reference.depth += 1
        began = time.perf_counter()
        try:
            return original(*args, **kwargs)
        finally:
            _Reference.depth -= 1
            _Reference.seconds += time.perf_counter() - began

    for module in list(sys.modules.values()):
        if getattr(module, "run_batch", None) is original:
            setattr(module, "run_batch", timed)  # noqa: B010 - a module bound by name


def pytest_configure(config: pytest.Config) -> None:
    """Time the reference runs from the start (before the test modules import them)."""
    del config
    _time_reference_runs()


@pytest.hookimpl(wrapper=True)
def pytest_runtest_protocol(item: pytest.Item, nextitem: pytest.Item | None) -> Generator[None]:
    """One row per test: wall, CPU (own and children's) and reference seconds."""
    del nextitem
    wall, cpu, reference = time.perf_counter(), _cpu_s(), _Reference.seconds
    try:
        return (yield)
    finally:
        _rows.append(
            {
                "test": item.nodeid,
                "wall_s": time.perf_counter() - wall,
                "cpu_s": _cpu_s() - cpu,
                "reference_s": _Reference.seconds - reference,
            }
        )


def pytest_sessionfinish(session: pytest.Session) -> None:
    """Write this process's rows (a worker's, or the only process's)."""
    del session
    folder = os.environ.get(OUT_ENV)
    if not folder or not _rows:
        return
    worker = os.environ.get("PYTEST_XDIST_WORKER", "main")
    path = Path(folder) / f"{worker}-{os.getpid()}.json"
    path.write_text(json.dumps(_rows), encoding="utf-8")
