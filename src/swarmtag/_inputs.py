"""Opening input files the one safe way: only regular files, refused in one line otherwise.

A FIFO, a device or a folder given where a file is expected would block a
reader forever or fail deep inside a parser; every reader of user files
(TOML, event logs, event tables, baselines) asks here first.
"""

from __future__ import annotations

import os
import stat
from pathlib import Path

from swarmtag.errors import SwarmtagError

__all__ = ["regular_file"]


def regular_file(path: str | os.PathLike[str], *, what: str, error: type[SwarmtagError]) -> Path:
    """``path`` if it names a readable regular file, else ``error`` naming the file and why.

    ``what`` names the kind of file in the messages (``"event log"``). The
    check uses ``stat`` and never opens the file, so a FIFO cannot block it.
    """
    name = os.fspath(path)
    try:
        mode = Path(path).stat().st_mode
    except FileNotFoundError:
        msg = f"{name}: no such {what}"
        raise error(msg) from None
    except (OSError, ValueError) as problem:  # ValueError: a NUL byte in the path
        reason = problem.strerror if isinstance(problem, OSError) else "not a valid path"
        msg = f"{name}: cannot read the {what} ({reason})"
        raise error(msg) from None
    if stat.S_ISDIR(mode):
        msg = f"{name}: is a folder, not the {what}"
        raise error(msg)
    if not stat.S_ISREG(mode):
        msg = f"{name}: is not a regular file (a FIFO, socket or device); the {what} must be one"
        raise error(msg)
    if not os.access(path, os.R_OK):
        msg = f"{name}: cannot read the {what} (permission denied)"
        raise error(msg)
    return Path(path)
