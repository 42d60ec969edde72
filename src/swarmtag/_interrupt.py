"""Ctrl-C that always works: a SIGINT handler that also leaves a flag for checkpoints.

Python raises ``KeyboardInterrupt`` at whatever bytecode runs when SIGINT
arrives; if that is Python code called from inside a C extension that
clears errors (numpy clears exceptions raised while it probes an object's
type for array protocols, such as an ``IntEnum`` member's metaclass
``__getattr__``), the interrupt is silently lost; if it is a finalizer or a
weakref callback (run during garbage collection), Python prints it as
"Exception ignored in ..." (or, from Cython, prints a whole traceback) and
carries on. ``install()`` quiets those (the flag keeps the interrupt). Long
loops (simulation ticks, bootstrap chunks, study chunks) call
``checkpoint()``, which re-raises a lost interrupt at the next step; for the
stretches with no checkpoint (imports, set-up inside a library) a watchdog
thread, started by the first SIGINT, sends SIGINT to the main thread again
every ``RESEND_S`` until the command line has taken the interrupt
(``acknowledge()``), while the main thread is not already handling it.
Without ``install()`` (library use) none of this runs.
"""

from __future__ import annotations

import _thread
import signal
import sys
import threading
import time

# Only signal at run time: ``swarmtag.cli.main`` imports this module first thing, and until
# ``install()`` has run a Ctrl-C ends in a traceback.
TYPE_CHECKING = False
if TYPE_CHECKING:
    from collections.abc import Callable
    from types import FrameType
    from typing import TypeVar

    T = TypeVar("T")

__all__ = [
    "RESEND_S",
    "acknowledge",
    "checkpoint",
    "deferred",
    "in_thread",
    "install",
    "interrupted",
]

RESEND_S = 0.2
"""Seconds between the watchdog's re-sends of a Ctrl-C that nobody has taken yet."""

_state = {"pending": False, "acknowledged": False, "watching": False}
_main: dict[str, int] = {}


_NATIVE_BOOKKEEPING = ("llvmlite.",)
"""Modules whose code hands native objects over: never interrupted mid-way (see ``_handler``)."""


def _handler(_signum: int, frame: FrameType | None) -> None:
    _flag()
    if frame is not None and frame.f_globals.get("__name__", "").startswith(_NATIVE_BOOKKEEPING):
        # llvmlite (numba's compiler) records after each native call who owns the LLVM
        # object: interrupted in between (a module linked into another, freed by LLVM,
        # but not yet detached), its finalizer frees it again and the process segfaults
        # at exit. Flagged only: the watchdog re-sends it RESEND_S later, out of there.
        return
    raise KeyboardInterrupt


def _flag() -> None:
    """Note the interrupt and start the watchdog (once) that keeps it from being lost."""
    _state["pending"] = True
    if not _state["watching"] and not _state["acknowledged"] and "thread" in _main:
        _state["watching"] = True
        _thread.start_new_thread(_watch, (_main["thread"],))


def _handling_interrupt(thread: int) -> bool:
    """Whether ``thread`` is inside an ``except``/``finally``/``__exit__`` of a Ctrl-C now."""
    current = sys._current_exceptions().get(thread)  # private, but the only way to look
    error = current[1] if isinstance(current, tuple) else current  # a 3-tuple before 3.12
    seen: set[int] = set()
    while isinstance(error, BaseException) and id(error) not in seen:
        if isinstance(error, KeyboardInterrupt):
            return True
        seen.add(id(error))
        error = error.__context__  # the CLI re-raises it as its own error, from None
    return False


def _watch(thread: int) -> None:
    """Re-send SIGINT to the main thread until the command line has taken the interrupt."""
    while True:
        time.sleep(RESEND_S)
        if _state["acknowledged"] or not _state["pending"]:
            _state["watching"] = False
            return
        if not _handling_interrupt(thread):
            # Lost (swallowed inside a library) or not yet seen: raise it again. A real
            # signal, not interrupt_main(), so that a blocking call in the main thread wakes.
            try:
                signal.pthread_kill(thread, signal.SIGINT)
            except OSError:  # the main thread is gone: the process is ending anyway
                _state["watching"] = False
                return


def acknowledge() -> None:
    """Tell the watchdog that the interrupt was taken (the command is ending with it)."""
    _state["acknowledged"] = True


def install() -> Callable[[], None]:
    """Route SIGINT through the flagging handler; returns a function that restores the old one.

    An interrupt Python cannot raise (it arrived inside a finalizer or a
    weakref callback) is kept by the flag and not printed: ``checkpoint()``
    raises it. Only the main thread may set signal handlers; elsewhere this
    does nothing.
    """
    _state.update(pending=False, acknowledged=False)
    try:
        previous = signal.signal(signal.SIGINT, _handler)
    except ValueError:  # not the main thread
        return lambda: None
    if hasattr(signal, "pthread_kill"):  # POSIX: the watchdog can re-send
        _main["thread"] = _thread.get_ident()
    previous_unraisable = sys.unraisablehook
    previous_except = sys.excepthook

    def unraisable(info: sys.UnraisableHookArgs) -> None:
        if info.exc_type is KeyboardInterrupt and _state["pending"]:
            return  # ours, swallowed where it arrived: checkpoint() raises it again
        previous_unraisable(info)

    def excepthook(kind: type[BaseException], value: BaseException, trace: object) -> None:
        # Cython's "unraisable" path prints a full traceback through sys.excepthook.
        if issubclass(kind, KeyboardInterrupt) and _state["pending"]:
            return
        previous_except(kind, value, trace)  # type: ignore[arg-type]

    sys.unraisablehook = unraisable
    sys.excepthook = excepthook

    def restore() -> None:
        _state["acknowledged"] = True  # first: the watchdog must not send to the old handler
        # The interrupt ended with what was installed: a library call after, say, an
        # in-process ``main()`` that a Ctrl-C ended must not meet it at its checkpoints.
        _state["pending"] = False
        _main.pop("thread", None)
        signal.signal(signal.SIGINT, previous)
        sys.unraisablehook = previous_unraisable
        sys.excepthook = previous_except

    return restore


def interrupted() -> bool:
    """Whether a SIGINT arrived since ``install()``."""
    return _state["pending"]


def checkpoint() -> None:
    """Raise ``KeyboardInterrupt`` if a SIGINT arrived, even one that something swallowed."""
    if _state["pending"]:
        raise KeyboardInterrupt


class deferred:  # noqa: N801 - used as ``with deferred():``, like contextlib's helpers
    """Hold Ctrl-C back for a short critical section; raise it when the section is done.

    Swaps the SIGINT handler (masking the signal would not do: another thread
    of the process may take it). Outside the main thread it only runs the body.
    """

    def __init__(self) -> None:
        self._arrived: list[int] = []
        self._previous: object = None
        self._swapped = False

    def __enter__(self) -> None:
        try:
            self._previous = signal.signal(signal.SIGINT, self._record)
            self._swapped = True
        except ValueError:  # not the main thread
            self._swapped = False

    def _record(self, signum: int, _frame: FrameType | None) -> None:
        self._arrived.append(signum)

    def __exit__(self, kind: object, value: object, traceback: object) -> None:
        if not self._swapped:
            return
        signal.signal(signal.SIGINT, self._previous)  # type: ignore[arg-type]
        if self._arrived and kind is None:
            if self._previous is _handler:
                _flag()
            raise KeyboardInterrupt


def in_thread(work: Callable[[], T]) -> T:
    """``work()``, run in a helper thread while this one waits, so that Ctrl-C is taken at once.

    For one long call into compiled code that lets go of the interpreter (OpenCV's
    decoding and marker detection do): run in the main thread, no signal handler
    could run until it returned. An interrupt leaves the helper to finish on its
    own (a daemon thread: the process does not wait for it); its result is dropped.
    Outside the main thread ``work`` simply runs.
    """
    if threading.current_thread() is not threading.main_thread():
        return work()
    outcome: list[tuple[bool, object]] = []
    done = threading.Event()

    def run() -> None:
        try:
            outcome.append((True, work()))
        except BaseException as error:  # noqa: BLE001 - handed to the waiting thread
            outcome.append((False, error))
        finally:
            done.set()

    threading.Thread(target=run, name="swarmtag-in-thread", daemon=True).start()
    while not done.wait(RESEND_S):
        checkpoint()
    ok, value = outcome[0]
    if not ok:
        raise value  # type: ignore[misc]
    return value  # type: ignore[return-value]
