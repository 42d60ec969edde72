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

__all__ = ["as_path", "check_path", "is_regular_file", "regular_file"]


def as_path(path: object, *, what: str, error: type[SwarmtagError]) -> Path:
    """``path`` as a ``Path`` if it can name a file at all (a str or path, not empty, no NUL)."""
    text = os.fspath(path) if isinstance(path, str | os.PathLike) else path
    if not isinstance(text, str):
        msg = f"{what}: expected a str or os.PathLike path, got {type(path).__name__}"
        raise error(msg)
    if not text or "\0" in text:
        msg = f"{what} {text!r} is empty or holds a NUL character"
        raise error(msg)
    return Path(text)


def is_regular_file(path: str | os.PathLike[str]) -> bool:
    """Whether ``path`` names a regular file; never raises.

    ``Path.is_file`` raises on a name too long for the platform (ENAMETOOLONG),
    so a long word given where a name or a file is accepted would fail there.
    """
    return os.path.isfile(path)  # noqa: PTH113 - Path.is_file raises ENAMETOOLONG


def check_path(path: str | os.PathLike[str], *, what: str, error: type[SwarmtagError]) -> Path:
    """``path`` if the system could name it (no NUL byte, no name or path too long), else ``error``.

    Checks that ``stat`` would raise on (instead of answering "no such file") are refused
    here with one line, before any ``exists()`` or ``is_dir()`` is asked.
    """
    name = os.fspath(path)
    try:
        os.stat(path)  # noqa: PTH116 - the error, not the answer, is wanted
    except (FileNotFoundError, NotADirectoryError):
        pass
    except (OSError, ValueError) as problem:
        reason = problem.strerror if isinstance(problem, OSError) else "not a valid path"
        if not isinstance(problem, PermissionError):
            msg = f"{what}: {name!r} cannot be used ({reason})"
            raise error(msg) from None
    return Path(path)


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
