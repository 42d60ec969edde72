"""Ctrl-C that always works: a SIGINT handler that also leaves a flag for checkpoints.

Python raises ``KeyboardInterrupt`` at whatever bytecode runs when SIGINT
arrives; if that is Python code called from inside a C extension that
clears errors (numpy clears exceptions raised while it probes an object's
type for array protocols, such as an ``IntEnum`` member's metaclass
``__getattr__``), the interrupt is silently lost; if it is a finalizer or a
weakref callback (run during garbage collection), Python prints it as
"Exception ignored in ..." and carries on. ``install()`` also quiets those
(the flag keeps the interrupt). The command line installs
``install()``; long loops (simulation ticks, bootstrap chunks, study chunks)
call ``checkpoint()``, which re-raises a lost interrupt at the next step.
Without ``install()`` (library use) ``checkpoint()`` does nothing.
"""

from __future__ import annotations

import signal
import sys

# Only signal at run time: ``swarmtag.cli.main`` imports this module first thing, and until
# ``install()`` has run a Ctrl-C ends in a traceback.
TYPE_CHECKING = False
if TYPE_CHECKING:
    from collections.abc import Callable
    from types import FrameType

__all__ = ["checkpoint", "deferred", "install", "interrupted"]

_state = {"pending": False}


def _handler(_signum: int, _frame: FrameType | None) -> None:
    _state["pending"] = True
    raise KeyboardInterrupt


def install() -> Callable[[], None]:
    """Route SIGINT through the flagging handler; returns a function that restores the old one.

    An interrupt Python cannot raise (it arrived inside a finalizer or a
    weakref callback) is kept by the flag and not printed: ``checkpoint()``
    raises it. Only the main thread may set signal handlers; elsewhere this
    does nothing.
    """
    _state["pending"] = False
    try:
        previous = signal.signal(signal.SIGINT, _handler)
    except ValueError:  # not the main thread
        return lambda: None
    previous_hook = sys.unraisablehook

    def unraisable(info: sys.UnraisableHookArgs) -> None:
        if info.exc_type is KeyboardInterrupt and _state["pending"]:
            return  # ours, swallowed where it arrived: checkpoint() raises it again
        previous_hook(info)

    sys.unraisablehook = unraisable

    def restore() -> None:
        signal.signal(signal.SIGINT, previous)
        sys.unraisablehook = previous_hook

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
            _state["pending"] = _state["pending"] or self._previous is _handler
            raise KeyboardInterrupt
