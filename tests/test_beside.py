"""Work forked beside the command: items in, steps and notes out, errors and deaths raised here."""

from __future__ import annotations

import contextlib
import multiprocessing
import os
import signal
import subprocess
import sys
import threading
import time
from collections.abc import Callable, Iterable
from pathlib import Path

import numpy as np
import pytest

from swarmtag import _beside
from swarmtag._atomic import WriteFailure
from swarmtag._beside import Beside, beside, can_fork, finish_all
from swarmtag.errors import ConfigError, ResourceError

pytestmark = pytest.mark.skipif(not can_fork(), reason="forks on Linux only")


class Squares:
    """A job that notes its process, its priority, and each item squared."""

    def __init__(self, fail: BaseException | None = None, die: bool = False) -> None:
        self.fail, self.die = fail, die
        self.prepared_in: int | None = None

    def prepare(self) -> None:
        self.prepared_in = os.getpid()

    def finish(self, items: Iterable[int], step: Callable[[str], None]) -> list[str]:
        notes = [f"prepared in {self.prepared_in}, niceness {os.nice(0)}"]
        for item in items:
            step(f"squaring {item}")
            if self.die:
                os.kill(os.getpid(), signal.SIGKILL)
            if self.fail is not None:
                raise self.fail
            notes.append(f"{item}^2 = {item * item} in {os.getpid()}")
        return notes


def test_items_go_to_the_child_and_its_steps_and_notes_come_back():
    job = Squares()
    steps: list[str] = []
    with beside(job) as (child,):
        for item in (2, 3):
            child.send(item, steps.append)
        notes = child.finish(steps.append)
    assert job.prepared_in is None  # prepared in the child, not here
    prepared, *squares = notes
    pid = int(squares[0].rsplit(" ", 1)[1])
    assert pid != os.getpid()
    assert prepared == f"prepared in {pid}, niceness {os.nice(0) + _beside.NICENESS}"
    assert squares == [f"2^2 = 4 in {pid}", f"3^2 = 9 in {pid}"]
    assert steps == ["squaring 2", "squaring 3"]


def test_an_error_in_the_child_is_raised_here_as_itself():
    with beside(Squares(fail=ConfigError("animation: bad"))) as (child,):
        child.send(1, lambda _: None)
        with pytest.raises(ConfigError, match=r"^animation: bad$"):
            child.finish(lambda _: None)


def test_a_write_failure_keeps_its_target_and_errno():
    failure = WriteFailure("no space left on device", "/out/run.gif", 28)
    with beside(Squares(fail=failure)) as (child,):
        child.send(1, lambda _: None)
        with pytest.raises(WriteFailure) as raised:
            child.finish(lambda _: None)
    assert (raised.value.path, raised.value.errno) == ("/out/run.gif", 28)
    assert str(raised.value) == "no space left on device while writing /out/run.gif"


class _Unpicklable(Exception):
    """An error that cannot be pickled, whoever taught exceptions to pickle (tblib does, once
    ``distributed`` is imported: then ``__init__``'s signature alone would not stop it)."""

    def __init__(self, a: int, b: int) -> None:
        super().__init__(f"{a} and {b}")
        self.held = threading.Lock()


def test_an_error_that_cannot_travel_comes_as_its_traceback():
    with beside(Squares(fail=_Unpicklable(1, 2))) as (child,):
        child.send(1, lambda _: None)
        with pytest.raises(RuntimeError, match="_Unpicklable: 1 and 2"):
            child.finish(lambda _: None)


def test_a_child_killed_without_a_word_is_a_resource_error():
    with beside(Squares(die=True)) as (child,):
        child.send(1, lambda _: None)
        with pytest.raises(ResourceError, match=r"ended before it was done \(killed by signal 9\)"):
            child.finish(lambda _: None)
        with pytest.raises(ResourceError, match="killed by signal 9"):  # and any later send
            child.send(2, lambda _: None)


class _Sleeper(Squares):
    def prepare(self) -> None:
        Path(os.environ["BESIDE_READY"]).touch()
        time.sleep(60)


def test_leaving_early_ends_the_child_at_once(tmp_path, monkeypatch):
    monkeypatch.setenv("BESIDE_READY", str(tmp_path / "ready"))
    began = time.monotonic()
    with beside(_Sleeper()) as (child,):
        while not (tmp_path / "ready").exists():
            time.sleep(0.01)
        process = child._process  # the child itself
    assert not process.is_alive()
    assert process.exitcode == 128 + signal.SIGTERM  # unwound, its own children ended
    assert time.monotonic() - began < 30


class _Swallowing(Squares):
    """Its SIGTERM is swallowed while it prepares, as an import in a C extension can swallow it."""

    def prepare(self) -> None:
        Path(os.environ["BESIDE_READY"]).touch()
        with contextlib.suppress(SystemExit):
            time.sleep(60)


def test_a_child_that_lost_its_sigterm_ends_at_its_next_read(tmp_path, monkeypatch):
    monkeypatch.setenv("BESIDE_READY", str(tmp_path / "ready"))
    with beside(_Swallowing()) as (child,):
        while not (tmp_path / "ready").exists():
            time.sleep(0.01)
        process = child._process
    assert not process.is_alive()
    assert process.exitcode != -signal.SIGKILL  # not killed after waiting _END_S for it


class _HeldBackCtrlC:
    """``deferred`` with a Ctrl-C that arrived during the fork: raised as the section ends."""

    def __enter__(self) -> None:
        pass

    def __exit__(self, kind: object, *rest: object) -> None:
        if kind is None:
            raise KeyboardInterrupt


def test_a_ctrl_c_held_back_over_the_fork_ends_the_child_it_started(monkeypatch):
    before = set(multiprocessing.active_children())
    monkeypatch.setattr(_beside, "deferred", _HeldBackCtrlC)
    with pytest.raises(KeyboardInterrupt):
        Beside.start(Squares())
    left = set(multiprocessing.active_children()) - before
    for process in left:  # a child left behind would block this process's exit
        process.kill()
    assert not left


def test_with_another_thread_running_the_work_stays_here():
    release = threading.Event()
    other = threading.Thread(target=release.wait)
    other.start()
    try:
        assert not can_fork()
        with beside(Squares(), 2) as children:
            assert children == []
        assert Beside.start(Squares()) is None
    finally:
        release.set()
        other.join()
    with beside(None, 2) as children:
        assert children == []


def test_several_children_each_get_their_own_items():
    steps: list[str] = []
    with beside(Squares(), 2) as children:
        assert len(children) == 2
        for item in range(5):
            children[item % 2].send(item, steps.append)
        first, second = (child.finish(steps.append) for child in children)
    assert [note.split(" in ")[0] for note in first[1:]] == ["0^2 = 0", "2^2 = 4", "4^2 = 16"]
    assert [note.split(" in ")[0] for note in second[1:]] == ["1^2 = 1", "3^2 = 9"]
    assert first[1].rsplit(" ", 1)[1] != second[1].rsplit(" ", 1)[1]  # two processes
    assert sorted(steps) == [f"squaring {item}" for item in range(5)]


class _Sums:
    """A job that sums each array it gets, and notes its dtype, shape and whether it may write."""

    def prepare(self) -> None:
        """Nothing to load."""

    def finish(self, items: Iterable[np.ndarray], step: Callable[[str], None]) -> list[str]:
        return [f"{a.dtype} {a.shape} {int(a.sum())} {a.flags.writeable}" for a in items]


def test_arrays_travel_as_their_bytes_and_other_items_pickled():
    frame = np.arange(24, dtype=np.uint8).reshape(2, 3, 4)
    strided = np.arange(12, dtype=np.int64).reshape(3, 4)[:, ::2]  # not contiguous: pickled
    with beside(_Sums()) as (child,):
        for item in (frame, strided, np.float32(2.5) * np.ones(3, dtype=np.float32)):
            child.send(item, lambda _: None)
        notes = child.finish(lambda _: None)
    assert notes == [
        "uint8 (2, 3, 4) 276 False",
        "int64 (3, 2) 30 True",
        "float32 (3,) 7 False",
    ]


def _gone(pid: int, within_s: float = 20.0) -> bool:
    """Whether process ``pid`` has ended (or is a zombie nobody reaps) within ``within_s``."""
    end = time.monotonic() + within_s
    while time.monotonic() < end:
        try:
            state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
        except (FileNotFoundError, ProcessLookupError):
            return True
        if state == "Z":
            return True
        time.sleep(0.05)
    return False


class _Waiting(Squares):
    """A job that says it is ready, then waits for items."""

    def prepare(self) -> None:
        Path(os.environ["BESIDE_READY"]).touch()


class _Nested(Squares):
    """A job whose finish starts a child of its own that waits for items (its pid to a file)."""

    def finish(self, items: Iterable[int], step: Callable[[str], None]) -> list[str]:
        with beside(_Sleeper()) as (grandchild,):
            Path(os.environ["BESIDE_GRANDCHILD"]).write_text(str(grandchild._process.pid))
            time.sleep(60)
        return []


def test_ending_a_child_ends_its_own_children(tmp_path, monkeypatch):
    monkeypatch.setenv("BESIDE_READY", str(tmp_path / "ready"))
    monkeypatch.setenv("BESIDE_GRANDCHILD", str(tmp_path / "grandchild"))
    with beside(_Nested()) as (child,):
        child.send(1, lambda _: None)
        while not (tmp_path / "ready").exists() or not (tmp_path / "grandchild").exists():
            time.sleep(0.01)
        grandchild = int((tmp_path / "grandchild").read_text())
    assert _gone(grandchild)


_KILLED_CALLER = """
import os, signal, sys, time
from pathlib import Path
sys.path.insert(0, sys.argv[1])
from tests.test_beside import _Waiting
from swarmtag._beside import beside
with beside(_Waiting(), 2) as children:
    while not Path(os.environ["BESIDE_READY"]).exists():
        time.sleep(0.01)
    print(" ".join(str(child._process.pid) for child in children), flush=True)
    os.kill(os.getpid(), signal.SIGKILL)
"""


def test_children_end_when_their_caller_is_killed(tmp_path):
    """Each child's read of the caller's pipe ends with the caller, though a sibling holds it."""
    done = subprocess.run(
        [sys.executable, "-c", _KILLED_CALLER, str(Path(__file__).parents[1])],
        env={**os.environ, "BESIDE_READY": str(tmp_path / "ready")},
        capture_output=True,
        text=True,
        timeout=60,
        check=False,
    )
    assert done.returncode == -signal.SIGKILL, done.stderr
    pids = [int(pid) for pid in done.stdout.split()]
    assert len(pids) == 2
    assert all(_gone(pid) for pid in pids)


def test_finishing_several_children_raises_the_first_error_without_waiting_for_the_rest(
    tmp_path, monkeypatch
):
    monkeypatch.setenv("BESIDE_READY", str(tmp_path / "ready"))
    began = time.monotonic()
    with (
        beside(_Sleeper(), 1) as (sleeping,),
        beside(Squares(fail=ConfigError("bad"))) as (failing,),
    ):
        failing.send(1, lambda _: None)
        with pytest.raises(ConfigError, match="bad"):
            finish_all([sleeping, failing], lambda _: None)
    assert time.monotonic() - began < 30  # the sleeper (60 s) was not waited for


class Cubes:
    """A service: answers each number asked with its cube and the process that computed it."""

    def __init__(self, fail: BaseException | None = None, die: bool = False) -> None:
        self.fail, self.die = fail, die

    def prepare(self) -> None:
        pass

    def answer(self, item: int) -> tuple[int, int, int]:
        if self.die:
            os.kill(os.getpid(), signal.SIGKILL)
        if self.fail is not None:
            raise self.fail
        return item**3, os.getpid(), os.nice(0)


def test_a_service_answers_each_question_in_its_process():
    assert isinstance(Cubes(), _beside.Service)
    assert not isinstance(Squares(), _beside.Service)
    with beside(Cubes()) as (child,):
        answers = [child.ask(item) for item in (2, 3, 4)]
        arrays = child.ask(np.arange(3))  # an array asked comes back as the array
    assert [cube for cube, _, _ in answers] == [8, 27, 64]
    assert {pid for _, pid, _ in answers} == {child._process.pid}
    assert child._process.pid != os.getpid()
    assert {nice for _, _, nice in answers} == {os.nice(0) + _beside.NICENESS}
    assert arrays[0].tolist() == [0, 1, 8]


def test_a_service_error_is_raised_at_the_question_and_a_death_is_a_resource_error():
    died = r"ended before it was done \(killed by signal 9\)"
    with (
        beside(Cubes(fail=ConfigError("no cubes today"))) as (failing,),
        pytest.raises(ConfigError, match=r"^no cubes today$"),
    ):
        failing.ask(1)
    with beside(Cubes(die=True)) as (dying,), pytest.raises(ResourceError, match=died):
        dying.ask(1)
