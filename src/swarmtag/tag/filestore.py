"""A tag store backed by a file, for software tags and bench setups.

Writes replace the file atomically (temporary file, fsync, rename), so a
crash leaves either the old record or the new one, never half of either.
"""

from __future__ import annotations

import os
from pathlib import Path

from swarmtag._atomic import atomic_write_bytes

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
        """Write ``record`` atomically, creating the store's folder on first use."""
        self.path.parent.mkdir(parents=True, exist_ok=True)
        atomic_write_bytes(self.path, record)
