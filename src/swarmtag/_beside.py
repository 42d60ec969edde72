"""Work done beside the caller in a forked process: it gets ready at once, then works on items.

A command that ends with slow output (``simulate --animate``: importing
matplotlib, then drawing the frames) can have that output's set-up done on
another core while its own work runs: the job's ``prepare`` starts as soon
as the process is forked, at a lower priority, and its ``finish`` (the
pictures themselves) works on the items the caller sends it (the recorded
runs, sent after the tables are printed; an animation's frames, sent to
the process writing the GIF). Arrays travel as their bytes, other items
pickled. Forked, the child shares what the caller has loaded and built; it
exits with ``os._exit`` (no exit handlers: the command's staging folders
are the command's), never sees a Ctrl-C (the caller ends it), and sends
its notes, or its error, back through a pipe. A ``Service`` (``simulate``'s
Mann-Whitney tests: importing scipy.stats takes half a second) answers each
item it is asked instead (``Beside.ask``). Where forking is not safe
(no ``fork``, macOS, or other threads running) there is no child and the
caller does the work itself.
"""

from __future__ import annotations

import contextlib
import multiprocessing
import os
import pickle
import signal
import sys
import threading
import traceback
import warnings
from collections.abc import Callable, Iterable, Iterator, Sequence
from contextlib import contextmanager
from multiprocessing.connection import Connection, wait
from typing import Any, Final, Protocol, runtime_checkable

import numpy as np

from swarmtag._interrupt import checkpoint, deferred
from swarmtag.errors import ResourceError

__all__ = ["NICENESS", "Beside", "Job", "Service", "beside", "can_fork", "finish_all"]

NICENESS: Final = 10
"""How much lower the child's priority is: the command's own work gets the cores first."""
_POLL_S: Final = 0.2
"""Longest wait for the child without looking for a Ctrl-C the handler could not raise."""
_END_S: Final = 5.0
"""Longest wait for an ended child to unwind before it is killed."""
_CALLER_ENDS: set[Connection] = set()
"""This process's ends of its children's pipes: a forked child closes its copies first, so
that each pipe ends (its reads see the end) when the process that holds it ends."""


class Job(Protocol):
    """Work in two parts: ``prepare`` (starts at once) and ``finish`` (on the items sent to it)."""

    def prepare(self) -> None:
        """Get ready (imports): nothing the user should see before the command's tables."""

    def finish(self, items: Iterable[Any], step: Callable[[str], None]) -> list[str]:
        """Work on ``items``, calling ``step`` as each part starts; notes of what was done."""


@runtime_checkable
class Service(Protocol):
    """Work that answers: ``prepare`` (starts at once), then ``answer`` to each item asked."""

    def prepare(self) -> None:
        """Get ready (imports), so that the first answer comes at once."""

    def answer(self, item: Any) -> Any:  # noqa: ANN401 - whatever the service answers
        """The answer to ``item`` (pickled on its way back)."""


def can_fork() -> bool:
    """Whether this process can fork a child safely: Linux, and no other Python thread running.

    macOS's system libraries are not safe after ``fork``; with another
    thread running, a lock it holds would stay locked in the child.
    """
    return (
        sys.platform.startswith("linux")
        and "fork" in multiprocessing.get_all_start_methods()
        and threading.active_count() == 1
    )


def _portable(error: BaseException) -> BaseException:
    """``error`` if it survives pickling, else a ``RuntimeError`` carrying its traceback."""
    try:
        pickle.loads(pickle.dumps(error))  # noqa: S301 - our own bytes, just made
    except Exception:  # noqa: BLE001 - any failure to round-trip means: send it as text
        text = "".join(traceback.format_exception(error)).rstrip()
        return RuntimeError(f"the process working beside the command failed:\n{text}")
    return error


def _received(pipe: Connection) -> Iterator[Any]:
    """The items the command sends, until it says the end."""
    while True:
        match pipe.recv():
            case ("item", item):
                yield item
            case ("array", str(dtype), tuple(shape)):
                yield np.frombuffer(pipe.recv_bytes(), dtype=np.dtype(dtype)).reshape(shape)
            case _:
                return


def _ended_by_signal(signum: int, _frame: object) -> None:
    """SIGTERM in a child: unwind (its own children are ended on the way), then exit."""
    raise SystemExit(128 + signum)


def _child(job: Job | Service, pipe: Connection) -> None:
    """The forked process: prepare, then finish on (or answer) what is sent; all goes back."""
    for inherited in list(_CALLER_ENDS):  # or a caller's death would not end their reads
        inherited.close()
    _CALLER_ENDS.clear()
    signal.signal(signal.SIGTERM, _ended_by_signal)
    os.nice(NICENESS)
    try:
        job.prepare()
        notes: list[str] = []
        if isinstance(job, Service):
            for item in _received(pipe):
                pipe.send(("answer", job.answer(item)))
        else:
            notes = job.finish(_received(pipe), lambda what: pipe.send(("step", what)))
        pipe.send(("done", notes))
    except SystemExit:  # ended (SIGTERM) by the caller, who wants no word back
        raise
    except BaseException as error:  # noqa: BLE001 - every failure is the command's to report
        with contextlib.suppress(OSError):  # the command has gone: nobody to tell
            pipe.send(("error", _portable(error)))
    finally:
        pipe.close()


class Beside:
    """A ``Job`` running in a forked child; use as a context manager (it is ended on exit)."""

    def __init__(self, process: Any, pipe: Connection) -> None:  # noqa: ANN401 - a ForkProcess
        """Hold the started ``process`` and this end of its ``pipe`` (use ``start``)."""
        self._process, self._pipe = process, pipe
        self._asking = threading.Lock()  # one question on the pipe at a time

    @classmethod
    def start(cls, job: Job | Service) -> Beside | None:
        """Fork a child running ``job`` (``prepare`` at once); None where ``can_fork`` is false."""
        if not can_fork():
            return None
        context = multiprocessing.get_context("fork")
        ours, theirs = context.Pipe()
        _CALLER_ENDS.add(ours)
        child = cls(context.Process(target=_child, args=(job, theirs)), ours)
        for stream in (sys.stdout, sys.stderr):  # or the child flushes our buffered text again
            stream.flush()
        try:
            with warnings.catch_warnings(), deferred():
                # Python 3.12+ warns of native threads too (OpenBLAS's pool): those
                # re-initialise at fork. The child starts deaf to Ctrl-C: the command ends it.
                warnings.filterwarnings("ignore", "This process .* is multi-threaded", Warning)
                mask = signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT})
                try:
                    child._process.start()
                finally:
                    signal.pthread_sigmask(signal.SIG_SETMASK, mask)
        except BaseException:
            # a Ctrl-C held back over the fork is raised here, the child running: nobody
            # else holds it to end it (the command's exit would wait for it for good)
            theirs.close()
            child.close()
            raise
        theirs.close()
        return child

    def __enter__(self) -> Beside:
        """The running child."""
        return self

    def __exit__(self, *exc: object) -> None:
        """End the child if it still runs (an error or Ctrl-C in the command), and reap it."""
        self.close()

    def send(self, item: object, step: Callable[[str], None]) -> None:
        """Send ``item`` to the job's ``finish`` (the steps reported so far go to ``step`` first).

        An error in the child is raised here, once it has said so.
        """
        while self._pipe.poll():
            self._take(self._receive(), step)
        try:
            if isinstance(item, np.ndarray) and item.flags.c_contiguous:  # its bytes, unpickled
                self._pipe.send(("array", item.dtype.str, item.shape))
                self._pipe.send_bytes(item.data.cast("B"))
            else:
                self._pipe.send(("item", item))
        except OSError:  # the child has ended: its error (or its death) says why
            finish_all([self], step)
            raise ResourceError(self._ended()) from None  # pragma: no cover - it said done

    def ask(self, item: object) -> Any:  # noqa: ANN401 - whatever the service answers
        """A ``Service``'s answer to ``item``, waited for (a Ctrl-C still taken); its error raised.

        A child that dies without a word is a ``ResourceError``, as in ``finish``.
        """
        with self._asking:
            self.send(item, _no_step)
            watched = [self._pipe, self._process.sentinel]
            while True:
                ready = wait(watched, timeout=_POLL_S)
                checkpoint()
                if ready:
                    message = self._receive() if self._pipe in ready else None
                    match message:
                        case ("answer", answer):
                            return answer
                        case _:
                            self._take(message, _no_step)

    def finish(self, step: Callable[[str], None]) -> list[str]:
        """Say the end of the items; pass on each ``step``; the job's notes, or its error raised.

        A child that dies without a word (killed: out of memory) is a
        ``ResourceError`` naming the signal or exit status.
        """
        return finish_all([self], step)[0]

    def _end_items(self) -> None:
        """Tell the child that no more items come."""
        with contextlib.suppress(OSError):  # ended already: its error or death says why
            self._pipe.send(("end",))

    def _receive(self) -> object:
        """The child's next message; None if it has gone (its end of the pipe closed)."""
        try:
            return self._pipe.recv()
        except (EOFError, OSError):
            return None

    def _take(self, message: object, step: Callable[[str], None]) -> list[str] | None:
        """Act on one ``message`` from the child: its notes when done, else None."""
        match message:
            case ("step", str(what)):
                step(what)
                return None
            case ("done", list(notes)):
                return [str(note) for note in notes]
            case ("error", BaseException() as error):
                raise error
            case _:
                raise ResourceError(self._ended())

    def _ended(self) -> str:
        """Why the child ended without a word: the signal that killed it, or its status."""
        self._process.join()
        code = self._process.exitcode
        how = f"killed by signal {-code}" if code < 0 else f"exit status {code}"
        return f"the process working beside the command ended before it was done ({how})"

    def close(self) -> None:
        """Stop the child (if still running) and release it and the pipe.

        Our end of the pipe closes before the wait: a child whose SIGTERM was
        swallowed (raised inside a C extension's import, which prints and drops
        it) then ends at its next read instead of when it is killed.
        """
        started = self._process.pid is not None  # not when the fork itself failed
        alive = started and self._process.is_alive()
        if alive:
            self._process.terminate()  # SIGTERM: it ends its own children on the way out
        _CALLER_ENDS.discard(self._pipe)
        self._pipe.close()
        if alive:
            self._process.join(_END_S)
            if self._process.is_alive():  # pragma: no cover - stuck where no signal is taken
                self._process.kill()
        if started:
            self._process.join()


def _no_step(_what: str) -> None:
    """A service reports no steps."""


def finish_all(children: Sequence[Beside], step: Callable[[str], None]) -> list[list[str]]:
    """``finish`` every child at once: each step passed on as it comes, from whichever child.

    Each child's notes, in the order of ``children``; the first error (or
    silent death) any of them reports is raised as soon as it comes.
    """
    for child in children:
        child._end_items()
    notes: dict[int, list[str]] = {}
    while len(notes) < len(children):
        pending = [(i, child) for i, child in enumerate(children) if i not in notes]
        watched = [p for _, child in pending for p in (child._pipe, child._process.sentinel)]
        ready = wait(watched, timeout=_POLL_S)
        checkpoint()
        for i, child in pending:
            pipe, sentinel = child._pipe, child._process.sentinel
            if pipe in ready or sentinel in ready:
                # a pipe is readable until its last message is read, even once its child ended
                done = child._take(child._receive() if pipe in ready else None, step)
                if done is not None:
                    notes[i] = done
    return [notes[i] for i in range(len(children))]


@contextmanager
def beside(job: Job | Service | None, count: int = 1) -> Iterator[list[Beside]]:
    """Up to ``count`` forked children running ``job``, ended on leaving; none where none can fork.

    With none, the caller does the work itself.
    """
    with contextlib.ExitStack() as stack:
        children: list[Beside] = []
        while job is not None and len(children) < count:
            child = Beside.start(job)
            if child is None:
                break
            children.append(stack.enter_context(child))
        yield children
