"""Ctrl-C: the flagging SIGINT handler and the checkpoint that re-raises a swallowed interrupt."""

from __future__ import annotations

import contextlib
import os
import signal
import subprocess
import sys

import pytest

from swarmtag import _interrupt


def test_checkpoint_does_nothing_until_an_interrupt_arrives():
    restore = _interrupt.install()
    try:
        _interrupt.checkpoint()
        assert not _interrupt.interrupted()
    finally:
        restore()


def test_a_swallowed_interrupt_is_raised_again_at_the_next_checkpoint():
    restore = _interrupt.install()
    try:
        # Swallowed, as numpy does to an exception raised inside its type probes:
        with contextlib.suppress(KeyboardInterrupt):
            os.kill(os.getpid(), signal.SIGINT)  # the handler runs at the next bytecode
        assert _interrupt.interrupted()
        with pytest.raises(KeyboardInterrupt):
            _interrupt.checkpoint()
    finally:
        restore()
    assert signal.getsignal(signal.SIGINT) is not _interrupt._handler


def test_install_resets_the_flag_and_restore_puts_back_the_old_handler():
    before = signal.getsignal(signal.SIGINT)
    restore = _interrupt.install()
    assert signal.getsignal(signal.SIGINT) is _interrupt._handler
    restore()
    assert signal.getsignal(signal.SIGINT) is before
    _interrupt.install()()
    assert not _interrupt.interrupted()


_FINALIZER_SCRIPT = """
import sys
from swarmtag import _interrupt

class Dying:
    def __del__(self):
        # a Ctrl-C that arrives while a finalizer runs: Python cannot raise it from here
        _interrupt._handler(2, None)

restore = _interrupt.install()
Dying()  # collected at once: its finalizer raises, Python calls the unraisable hook
print("carried on", _interrupt.interrupted(), flush=True)
try:
    _interrupt.checkpoint()
except KeyboardInterrupt:
    print("raised at the checkpoint", flush=True)
restore()

class Other:
    def __del__(self):
        raise ValueError("not ours")

Other()  # other errors in finalizers are still reported as usual
"""


def test_an_interrupt_inside_a_finalizer_is_kept_quietly_for_the_checkpoint():
    done = subprocess.run(
        [sys.executable, "-c", _FINALIZER_SCRIPT], capture_output=True, text=True, check=True
    )
    assert done.stdout.splitlines() == ["carried on True", "raised at the checkpoint"]
    assert "KeyboardInterrupt" not in done.stderr  # nothing printed for our interrupt
    assert "ValueError: not ours" in done.stderr  # the previous hook still reports the rest
