"""Ctrl-C: the flagging SIGINT handler and the checkpoint that re-raises a swallowed interrupt."""

from __future__ import annotations

import contextlib
import os
import signal
import subprocess
import sys

import pytest

from swarmtag import _interrupt

pytestmark = pytest.mark.serial  # re-sends within 2 RESEND_S: not beside other tests' load


def _run_script(script: str) -> subprocess.CompletedProcess[str]:
    """Run ``script`` in a fresh interpreter (its own handler and watchdog); its output."""
    return subprocess.run(
        [sys.executable, "-c", script], capture_output=True, text=True, check=True, timeout=30
    )


def test_checkpoint_does_nothing_until_an_interrupt_arrives():
    restore = _interrupt.install()
    try:
        _interrupt.checkpoint()
        assert not _interrupt.interrupted()
    finally:
        restore()


@pytest.mark.usefixtures("no_resent_interrupt")
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


@pytest.mark.usefixtures("no_resent_interrupt")
def test_after_restore_a_past_interrupt_is_not_raised_at_checkpoints():
    # library use after an in-process command that a Ctrl-C ended: nothing is pending
    restore = _interrupt.install()
    try:
        with contextlib.suppress(KeyboardInterrupt):
            os.kill(os.getpid(), signal.SIGINT)
    finally:
        restore()
    assert not _interrupt.interrupted()
    _interrupt.checkpoint()


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
    done = _run_script(_FINALIZER_SCRIPT)
    assert done.stdout.splitlines() == ["carried on True", "raised at the checkpoint"]
    assert "KeyboardInterrupt" not in done.stderr  # nothing printed for our interrupt
    assert "ValueError: not ours" in done.stderr  # the previous hook still reports the rest


_LOST_SCRIPT = """
import contextlib, os, signal, sys, threading, time
from swarmtag import _interrupt

restore = _interrupt.install()
with contextlib.suppress(KeyboardInterrupt):  # swallowed inside a library, no checkpoint near
    os.kill(os.getpid(), signal.SIGINT)
    time.sleep(1)
begin = time.monotonic()
try:
    {wait}
    print("not raised", flush=True)
except KeyboardInterrupt:
    print("raised again", round(time.monotonic() - begin, 2), flush=True)
    _interrupt.acknowledge()
"""


@pytest.mark.skipif(not hasattr(signal, "pthread_kill"), reason="POSIX signals")
@pytest.mark.parametrize(
    "wait",
    ["while time.monotonic() - begin < 5: pass", "threading.Event().wait(5)"],
    ids=["busy", "blocked"],
)
def test_a_lost_interrupt_is_sent_again_by_the_watchdog_even_into_a_blocking_call(wait):
    script = _LOST_SCRIPT.format(wait=wait)
    done = _run_script(script)
    word, again, seconds = done.stdout.split()
    assert (word, again) == ("raised", "again"), done.stdout
    assert float(seconds) <= 2 * _interrupt.RESEND_S + 0.2


_HANDLING_SCRIPT = """
import os, signal, sys, time
from swarmtag import _interrupt

restore = _interrupt.install()
events = []
try:
    try:
        os.kill(os.getpid(), signal.SIGINT)
        time.sleep(1)
    except KeyboardInterrupt:
        time.sleep(1)  # a long clean-up while the interrupt is being handled: not disturbed
        events.append("cleaned up")
    _interrupt.acknowledge()  # taken: nothing is sent after this either
    time.sleep(1)
    events.append("quiet after")
except KeyboardInterrupt:
    events.append("sent again")
print(" / ".join(events), flush=True)
"""


@pytest.mark.skipif(not hasattr(signal, "pthread_kill"), reason="POSIX signals")
def test_the_watchdog_leaves_an_interrupt_being_handled_or_taken_alone():
    done = _run_script(_HANDLING_SCRIPT)
    assert done.stdout.strip() == "cleaned up / quiet after"


_CYTHON_SCRIPT = """
import ctypes
from swarmtag import _interrupt

restore = _interrupt.install()
try:
    _interrupt._handler(2, None)
except KeyboardInterrupt:
    pass
_interrupt.acknowledge()
# C code printing an error it cannot raise with PyErr_Print, as Cython's "unraisable" path
# does with a full traceback (PyRun_SimpleString prints its failure the same way):
ctypes.pythonapi.PyRun_SimpleString(b"raise KeyboardInterrupt")
print("carried on", flush=True)
restore()
ctypes.pythonapi.PyRun_SimpleString(b"raise ValueError('not ours')")
"""


def test_an_interrupt_printed_as_a_traceback_by_a_c_extension_is_kept_quiet():
    done = _run_script(_CYTHON_SCRIPT)
    assert done.stdout.strip() == "carried on"
    assert "KeyboardInterrupt" not in done.stderr
    assert "ValueError: not ours" in done.stderr  # other errors are printed as before


_BOOKKEEPING_SCRIPT = """
import os, signal, time
from swarmtag import _interrupt

restore = _interrupt.install()
steps = []
# llvmlite's link_modules: a native call that frees a module, then the wrapper's detach().
linker = {"__name__": "llvmlite.binding.linker", "os": os, "signal": signal, "steps": steps}
exec(
    "def link_modules():\\n"
    "    os.kill(os.getpid(), signal.SIGINT)  # arrives right after the native call\\n"
    "    steps.append('detached')\\n",
    linker,
)
try:
    linker["link_modules"]()
    steps.append("returned")
    time.sleep(5)
    steps.append("never interrupted")
except KeyboardInterrupt:
    steps.append("raised")
print(" ".join(steps), flush=True)
"""


@pytest.mark.skipif(
    not hasattr(signal, "pthread_kill"), reason="the watchdog's re-send needs pthread_kill (POSIX)"
)
def test_an_interrupt_inside_llvmlite_s_bookkeeping_is_raised_after_it():
    # Raised between LLVM freeing a module and its wrapper's detach(), the wrapper's
    # finalizer freed it again at exit: a segfault after "aborted". The watchdog re-sends.
    done = _run_script(_BOOKKEEPING_SCRIPT)
    assert done.stdout.split() == ["detached", "returned", "raised"], done.stdout + done.stderr


@pytest.mark.parametrize("interrupted", [True, False], ids=["after-ctrl-c", "no-ctrl-c"])
def test_an_import_broken_by_a_ctrl_c_ends_as_aborted(monkeypatch, capsys, interrupted):
    # A Ctrl-C inside numpy's C import, or while a fresh checkout's source is compiled,
    # reaches the CLI as an ImportError or SyntaxError rather than a KeyboardInterrupt.
    from swarmtag.cli import main

    monkeypatch.setitem(sys.modules, "swarmtag.cli._main", None)  # its import fails
    monkeypatch.setattr(_interrupt, "interrupted", lambda: interrupted)
    if interrupted:
        with pytest.raises(SystemExit) as ended:
            main(["--help"])
        assert ended.value.code == 130
        assert capsys.readouterr().err == "swarmtag: error: aborted\n"
    else:
        with pytest.raises(ImportError):
            main(["--help"])
