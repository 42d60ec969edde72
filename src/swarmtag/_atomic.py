"""Atomic file replacement: a reader sees the old file or the new one, never half of either.

Used wherever swarmtag writes a file a user or a tag relies on (event logs,
tag records): write a temporary file in the same folder, flush it to disk,
rename it over the target, then flush the folder entry.
"""

from __future__ import annotations

import os
import secrets
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

__all__ = ["atomic_path", "atomic_write_bytes", "fsync_folder"]


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
    """
    target = Path(path)
    folder = target.parent
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
