"""A tag store backed by a file, for software tags and bench setups.

Writes replace the file atomically (temporary file, fsync, rename), so a
crash leaves either the old record or the new one, never half of either. A
crash (SIGKILL, power loss) in the middle of a save can leave that temporary
file behind; the next ``FileStore`` for the same record (the next boot)
removes it. Only this record's own temporaries are touched.
"""

from __future__ import annotations

import os
import re
from pathlib import Path

from swarmtag._atomic import atomic_write_bytes
from swarmtag._inputs import as_path
from swarmtag.errors import StateRecordError
from swarmtag.tag._arguments import as_bytes

__all__ = ["FileStore"]

# swarmtag._atomic names the temporary file of ``name`` ".{name}.{12 hex digits}.tmp".
_TEMP_NAME = r"\.{name}\.[0-9a-f]{{12}}\.tmp"


def _check_path(path: object) -> Path:
    """``path`` as a ``Path`` if it can name a record file; else ``StateRecordError``."""
    target = as_path(path, what="FileStore path", error=StateRecordError)
    try:
        if target.is_dir():
            raise StateRecordError(
                f"FileStore path {target} is a folder; give the record file's path inside it, "
                f"e.g. {target / 'tag.bin'}"
            )
        existing = next((folder for folder in target.parents if folder.exists()), None)
    except OSError as error:
        raise StateRecordError(f"FileStore path {target}: {error.strerror or error}") from None
    if existing is not None and not existing.is_dir():
        raise StateRecordError(f"FileStore path {target}: {existing} is a file, not a folder")
    return target


class FileStore:
    """Persist one tag's record in ``path`` with atomic replace; one store per file at a time.

    Creating the store (the tag booting) removes temporary files a killed save
    left next to the record. A ``path`` that is a folder, not a str or
    os.PathLike, or inside a file is refused with ``StateRecordError``.
    """

    def __init__(self, path: str | os.PathLike[str]) -> None:
        self.path = _check_path(path)
        self._remove_stale_temporaries()

    def _remove_stale_temporaries(self) -> None:
        """Delete ``.{name}.{hex}.tmp`` files of this record: leftovers of an interrupted save."""
        pattern = re.compile(_TEMP_NAME.format(name=re.escape(self.path.name)))
        folder = self.path.parent
        try:
            entries = list(folder.iterdir())
        except FileNotFoundError:  # no folder yet: nothing was ever saved
            return
        except OSError as error:
            raise StateRecordError(
                f"FileStore cannot list {folder} to clean up: {error.strerror or error}"
            ) from None
        for entry in entries:
            if pattern.fullmatch(entry.name) and not entry.is_symlink() and entry.is_file():
                entry.unlink(missing_ok=True)

    def load(self) -> bytes | None:
        """The saved record, or ``None`` if the file does not exist yet."""
        try:
            return self.path.read_bytes()
        except FileNotFoundError:
            return None
        except (IsADirectoryError, NotADirectoryError):
            raise StateRecordError(
                f"FileStore path {self.path} is a folder or lies inside a file"
            ) from None

    def save(self, record: bytes) -> None:
        """Write ``record`` atomically, creating the store's folder on first use."""
        data = as_bytes("record", record, StateRecordError)
        try:
            self.path.parent.mkdir(parents=True, exist_ok=True)
        except (FileExistsError, NotADirectoryError):
            raise StateRecordError(
                f"FileStore cannot create the folder of {self.path}: a file is in the way"
            ) from None
        if self.path.is_dir():
            raise StateRecordError(f"FileStore path {self.path} is a folder, not a record file")
        atomic_write_bytes(self.path, data)
