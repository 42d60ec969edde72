"""Threads for computing: how many, and a map on them that keeps order, errors and Ctrl-C."""

from __future__ import annotations

import os
import threading
import time

import pytest

from swarmtag import _threads
from swarmtag._threads import default_threads, map_in_threads


def _cores() -> int:
    if hasattr(os, "sched_getaffinity"):
        return len(os.sched_getaffinity(0))
    return os.cpu_count() or 1


@pytest.mark.parametrize(("value", "expected"), [("3", 3), ("1", 1), ("0", None), ("x", None)])
def test_default_threads_is_swarmtag_threads_else_the_usable_cores(monkeypatch, value, expected):
    monkeypatch.setenv("SWARMTAG_THREADS", value)
    assert default_threads() == (expected or _cores())


def test_the_results_come_in_order_from_several_threads():
    names: set[str] = set()
    both = threading.Barrier(2, timeout=10)  # two items at once: the map is on two threads

    def work(item: int) -> int:
        names.add(threading.current_thread().name)
        if item < 2:
            both.wait()
        return item * item

    assert map_in_threads(work, list(range(6)), 2) == [0, 1, 4, 9, 16, 25]
    assert len(names) == 2
    assert threading.current_thread().name not in names


def test_one_thread_runs_everything_here():
    seen = map_in_threads(lambda _: threading.current_thread(), [1, 2, 3], 1)
    assert seen == [threading.current_thread()] * 3


def test_the_first_error_in_item_order_is_raised():
    def work(item: int) -> int:
        if item == 3:
            raise ValueError("three")
        if item == 1:
            time.sleep(0.2)  # fails after item 3 has
            raise KeyError("one")
        return item

    with pytest.raises(KeyError, match="one"):
        map_in_threads(work, [0, 1, 2, 3], 2)


def test_a_ctrl_c_flagged_while_waiting_is_raised_without_waiting_for_the_work(monkeypatch):
    release = threading.Event()
    calls = []

    def interrupted() -> None:
        calls.append(time.monotonic())
        raise KeyboardInterrupt

    monkeypatch.setattr(_threads, "checkpoint", interrupted)
    begin = time.monotonic()
    try:
        with pytest.raises(KeyboardInterrupt):
            map_in_threads(lambda _: release.wait(30), [1, 2, 3], 2)
    finally:
        release.set()
    assert calls
    assert time.monotonic() - begin < 5  # the waiting thread took it: the work still blocks
