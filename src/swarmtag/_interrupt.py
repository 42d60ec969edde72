"""Ctrl-C that always works: a SIGINT handler that also leaves a flag for checkpoints.

Python raises ``KeyboardInterrupt`` at whatever bytecode runs when SIGINT
arrives; if that is Python code called from inside a C extension that
clears errors (numpy clears exceptions raised while it probes an object's
type for array protocols, such as an ``IntEnum`` member's metaclass
``__getattr__``), the interrupt is silently lost. The command line installs
``install()``; long loops (simulation ticks, bootstrap chunks, study chunks)
call ``checkpoint()``, which re-raises a lost interrupt at the next step.
Without ``install()`` (library use) ``checkpoint()`` does nothing.
"""

from __future__ import annotations

import signal
import threading
from collections.abc import Callable
from types import FrameType

__all__ = ["checkpoint", "install", "interrupted"]

_state = {"pending": False}


def _handler(_signum: int, _frame: FrameType | None) -> None:
    _state["pending"] = True
    raise KeyboardInterrupt


def install() -> Callable[[], None]:
    """Route SIGINT through the flagging handler; returns a function that restores the old one.

    Only the main thread may set signal handlers; elsewhere this does nothing.
    """
    _state["pending"] = False
    if threading.current_thread() is not threading.main_thread():
        return lambda: None
    previous = signal.signal(signal.SIGINT, _handler)

    def restore() -> None:
        signal.signal(signal.SIGINT, previous)

    return restore


def interrupted() -> bool:
    """Whether a SIGINT arrived since ``install()``."""
    return _state["pending"]


def checkpoint() -> None:
    """Raise ``KeyboardInterrupt`` if a SIGINT arrived, even one that something swallowed."""
    if _state["pending"]:
        raise KeyboardInterrupt
