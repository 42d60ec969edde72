"""The ``swarmtag`` command line.

Each command group lives in its own module; ``_main`` assembles them and turns
every refusal (bad input, usage errors of the CLI framework) into one line on
stderr and exit status 2, and Ctrl-C into ``swarmtag: error: aborted`` and 130.
This module stays import-light so that Ctrl-C is handled from the first
moment: the commands (numpy, click, ...) are imported inside ``main``.
"""

from __future__ import annotations

import sys

TYPE_CHECKING = False  # not typing's: importing typing would delay the handler by ~10 ms
if TYPE_CHECKING:
    from collections.abc import Sequence

__all__ = ["main"]


def main(argv: Sequence[str] | None = None) -> None:
    """Run the command line (see ``swarmtag --help``); exits with 0, 2 or 130."""
    from swarmtag._interrupt import (  # noqa: PLC0415 - before the imports
        acknowledge,
        install,
        interrupted,
    )

    restore = install()
    try:
        try:
            from swarmtag.cli._main import run  # noqa: PLC0415 - numpy, click, rich load here
        except (KeyboardInterrupt, ImportError, SyntaxError, RuntimeError) as error:
            # A Ctrl-C inside a C extension's import (numpy's) or while a source is compiled
            # (a fresh checkout has no bytecode yet; "\N{...}" loads unicodedata) surfaces
            # as an ImportError or SyntaxError, and inside a class's creation (a dataclass
            # field's __set_name__) as a RuntimeError: with the interrupt flagged, it is the
            # Ctrl-C.
            if not isinstance(error, KeyboardInterrupt) and not interrupted():
                raise
            acknowledge()
            print("swarmtag: error: aborted", file=sys.stderr)
            sys.exit(130)
        run(argv)
    except SystemExit as ending:
        if argv is None and interrupted():
            _end_interrupted(ending.code)
        raise
    finally:
        if argv is None:
            # This process is the command and ends with it: a Ctrl-C from here on (exit
            # handlers, interpreter shutdown) could only turn its exit status into a
            # traceback or a death by signal. Ignored, it ends with the status it has.
            import gc  # noqa: PLC0415 - built in
            import signal  # noqa: PLC0415 - loaded already, by install()

            signal.signal(signal.SIGINT, signal.SIG_IGN)
            # The interpreter's last cyclic collections at exit walk every object the
            # command loaded (numba's types, matplotlib, ...): 0.3-0.6 s, which made a
            # Ctrl-C end that much later. Frozen, they are skipped; outputs are closed by now.
            gc.freeze()
        else:
            restore()


def _end_interrupted(code: object) -> None:
    """End an interrupted command's process with ``code`` now, its objects never finalized.

    A Ctrl-C can land between a native library's call and the Python bookkeeping
    after it: inside numba's compiler, llvmlite links a module into another (LLVM
    frees it) but the interrupt comes before its wrapper is told, and the
    wrapper's finalizer at the interpreter's shutdown frees it again (a segfault,
    exit -11, after the ``aborted`` line). The command's own clean-up has run by
    now (``finally`` blocks, outputs removed, stores closed); the atexit handlers
    still run (multiprocessing's), then the process ends without the teardown.
    """
    import atexit  # noqa: PLC0415 - built in
    import contextlib  # noqa: PLC0415 - loaded already
    import os  # noqa: PLC0415 - loaded already
    import signal  # noqa: PLC0415 - loaded already, by install()

    signal.signal(signal.SIGINT, signal.SIG_IGN)  # the status is decided: keep it
    status = code if isinstance(code, int) else (0 if code is None else 1)
    if code is not None and not isinstance(code, int):
        print(code, file=sys.stderr)  # as the interpreter prints a message given to exit()
    atexit._run_exitfuncs()  # private, but the only way to run them without the teardown
    for stream in (sys.stdout, sys.stderr):
        with contextlib.suppress(OSError, ValueError):  # closed, or a pipe with no reader
            stream.flush()
    os._exit(status)
