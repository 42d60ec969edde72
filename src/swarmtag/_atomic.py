"""Atomic file replacement, and the one translation of a failed write into one line.

Used wherever swarmtag writes a file a user or a tag relies on (event logs,
tag records): write a temporary file in the same folder, flush it to disk,
rename it over the target, then flush the folder entry.

A write the device refuses (full, over quota, read-only, a file too large
for it, an I/O error) is ``WriteFailure``, an ``OutputError`` that names the
file: ``no space left on device while writing out/report.html``. On the
command line it is one line and exit status 2; the temporary file is gone
and the target is as it was.
"""

from __future__ import annotations

import errno
import os
import secrets
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

from swarmtag.errors import OutputError

__all__ = [
    "WRITE_ERRNOS",
    "WriteFailure",
    "atomic_path",
    "atomic_write_bytes",
    "failures_named",
    "fsync_folder",
    "write_failure",
    "write_failure_in_text",
]

WRITE_ERRNOS = frozenset({errno.ENOSPC, errno.EDQUOT, errno.EROFS, errno.EFBIG, errno.EIO})
"""The errors by which a device refuses a write: no fault of the command or its input."""


def _reason(code: int) -> str:
    """The system's words for ``code``, starting in lower case: ``no space left on device``."""
    text = os.strerror(code)
    return text[:1].lower() + text[1:]


class WriteFailure(OutputError, OSError):
    """The device refused a write of ``path`` (``reason``: full, read-only, quota, I/O error).

    An ``OutputError`` (the command line prints it as one line, exit 2) and
    still an ``OSError`` with its ``errno``, so that code which guards its
    state against a failed save (the tag server, counter files) handles it
    as before.
    """

    def __init__(self, reason: str, path: str | os.PathLike[str], code: int = errno.EIO) -> None:
        super().__init__(f"{reason} while writing {os.fspath(path)}")
        self.reason = reason
        self.path = os.fspath(path)
        self.errno = code
        self.strerror = reason

    def __str__(self) -> str:
        return f"{self.reason} while writing {self.path}"

    def __reduce__(self) -> tuple[type[WriteFailure], tuple[str, str, int]]:
        """Pickled as its three arguments (sent from a process drawing beside the command)."""
        return (type(self), (self.reason, self.path, self.errno or errno.EIO))


def write_failure(problem: BaseException, path: str | os.PathLike[str]) -> WriteFailure | None:
    """``problem`` as a ``WriteFailure`` of ``path`` if the device refused the write; else None."""
    if isinstance(problem, WriteFailure):
        return WriteFailure(problem.reason, path, problem.errno or errno.EIO)
    if isinstance(problem, OSError) and problem.errno in WRITE_ERRNOS:
        return WriteFailure(_reason(problem.errno), path, problem.errno)
    return None


def write_failure_in_text(text: str, path: str | os.PathLike[str]) -> WriteFailure | None:
    """A ``WriteFailure`` of ``path`` if a library's message ``text`` names one; else None.

    For libraries that report the system's error as text only (DuckDB).
    """
    folded = text.lower()
    for code in sorted(WRITE_ERRNOS):
        if _reason(code).lower() in folded:
            return WriteFailure(_reason(code), path, code)
    return None


@contextmanager
def failures_named(path: str | os.PathLike[str]) -> Iterator[None]:
    """Turn a write the device refused inside the block into ``WriteFailure`` naming ``path``.

    A ``WriteFailure`` from a nested block keeps the file it names.
    """
    try:
        yield
    except WriteFailure:
        raise
    except OSError as problem:
        failure = write_failure(problem, path)
        if failure is None:
            raise
        raise failure from None


def fsync_folder(folder: Path) -> None:
    """Flush the folder entry, so a new file's name survives a power loss (POSIX only)."""
    if hasattr(os, "O_DIRECTORY"):
        fd = os.open(folder, os.O_RDONLY | os.O_DIRECTORY)
        try:
            os.fsync(fd)
        finally:
            os.close(fd)


def _new_temp(folder: Path, name: str) -> Path:
    """Create an empty, unique temporary file; unlike mkstemp it honours the umask (0o666)."""
    while True:
        temp = folder / f".{name}.{secrets.token_hex(6)}.tmp"
        try:
            os.close(os.open(temp, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o666))
        except FileExistsError:  # pragma: no cover - 48 random bits
            continue
        except BaseException:  # a Ctrl-C just as it was created: leave no temporary file
            temp.unlink(missing_ok=True)
            raise
        return temp


@contextmanager
def atomic_path(path: str | os.PathLike[str]) -> Iterator[Path]:
    """Yield a temporary path to write; on success it replaces ``path``, on error it is removed.

    The folder must exist: a mistyped folder is an error, not a new folder.
    A write the device refuses, in the block or after it, is ``WriteFailure``
    naming ``path``.
    """
    target = Path(path)
    folder = target.parent
    with failures_named(target):
        temp = _new_temp(folder, target.name)
        try:
            yield temp
            with temp.open("rb+") as handle:
                os.fsync(handle.fileno())
            temp.replace(target)
        except BaseException:
            temp.unlink(missing_ok=True)
            raise
        fsync_folder(folder)


def atomic_write_bytes(path: str | os.PathLike[str], data: bytes) -> None:
    """Replace ``path`` with ``data`` atomically."""
    with atomic_path(path) as temp:
        temp.write_bytes(data)
