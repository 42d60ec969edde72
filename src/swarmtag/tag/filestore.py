"""A tag store backed by a file, for software tags and bench setups.

Writes go to a temporary file in the same folder, are flushed to disk and
then renamed over the old record, so a crash leaves either the old record or
the new one, never half of either.
"""

from __future__ import annotations

import os
import tempfile
from pathlib import Path

__all__ = ["FileStore"]


class FileStore:
    """Persist one tag's record in ``path`` with atomic replace."""

    def __init__(self, path: str | os.PathLike[str]) -> None:
        self.path = Path(path)

    def load(self) -> bytes | None:
        """The saved record, or ``None`` if the file does not exist yet."""
        try:
            return self.path.read_bytes()
        except FileNotFoundError:
            return None

    def save(self, record: bytes) -> None:
        """Write ``record`` atomically (temp file, fsync, rename, fsync of the folder)."""
        folder = self.path.parent
        folder.mkdir(parents=True, exist_ok=True)
        fd, temp = tempfile.mkstemp(prefix=f".{self.path.name}.", dir=folder)
        try:
            with os.fdopen(fd, "wb") as handle:
                handle.write(record)
                handle.flush()
                os.fsync(handle.fileno())
            Path(temp).replace(self.path)
        except BaseException:
            Path(temp).unlink(missing_ok=True)
            raise
        if hasattr(os, "O_DIRECTORY"):
            dir_fd = os.open(folder, os.O_RDONLY | os.O_DIRECTORY)
            try:
                os.fsync(dir_fd)
            finally:
                os.close(dir_fd)
