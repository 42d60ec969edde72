"""Ctrl-C: the flagging SIGINT handler and the checkpoint that re-raises a swallowed interrupt."""

from __future__ import annotations

import contextlib
import os
import signal

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
