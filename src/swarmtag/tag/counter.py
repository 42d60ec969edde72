"""A writer's counters on disk: each writer id's last counter, reserved before a write is sent.

A tag accepts a write only if its counter is above the highest it has
accepted from that writer id (``TagModel``; one entry per writer id, not per
writer and tag). So a writer keeps **one counter per writer id**, shared by
every tag it writes to: every tag then sees a strictly increasing sequence
from it, whatever order the writer visits the tags in, and a write signed
for one tag is useless on another (the target is inside the MAC). A counter
per (writer, tag) would work as well but would grow with the number of tags
and break when a marker id is reused.

``CounterFile.reserve`` writes the new counter to disk (temporary file,
fsync, rename, fsync of the folder) and only then returns it for signing:

- a crash after reserving and before sending only skips that value, which
  is safe (tags need increasing counters, not consecutive ones);
- a restart can never sign an old counter again, so a writer is never
  locked out of a tag by its own earlier writes (``ReplayedWrite``), and
  two different writes never carry one writer id and counter.

The file is ASCII text, one line per writer id, sorted, each ending in a
line feed::

    swarmtag-writer-counters-v1
    <writer id 0-65535> <last counter used 0-4294967295>

On POSIX systems a reservation holds an exclusive ``flock`` on the folder,
so two processes using the same file never reserve the same value. The
parsing and formatting (``parse_counters``, ``format_counters``) are pure
and take time linear in the file's size (a full table of 65,536 writers is
at most about 1.1 MB).

A write reads the file once: ``check`` (before the radio) parses it and
keeps the table with the file's identity (device, inode, size, modification
and change times); ``reserve``, under the lock, reuses that table when the
file's identity is unchanged and the file had settled when it was read (its
change time at least ``_SETTLED_NS`` before the read, so no later file can
carry the same identity), and reads it again otherwise.
"""

from __future__ import annotations

import itertools
import os
import re
import stat
import time
from collections.abc import Iterator, Mapping
from contextlib import contextmanager
from pathlib import Path
from types import MappingProxyType
from typing import Final

from swarmtag._atomic import atomic_write_bytes
from swarmtag._inputs import as_path
from swarmtag.errors import CounterFileError, FieldRangeError
from swarmtag.tag._arguments import check_int
from swarmtag.tag.write import MAX_COUNTER

try:
    import fcntl
except ImportError:  # pragma: no cover - Windows: no flock; one writer process per file there
    fcntl = None  # type: ignore[assignment]

__all__ = ["COUNTER_FILE_HEADER", "CounterFile", "format_counters", "parse_counters"]

COUNTER_FILE_HEADER: Final = "swarmtag-writer-counters-v1"
"""First line of a counter file."""
_MAX_WRITER: Final = 0xFFFF
_LINE: Final = re.compile(r"(0|[1-9][0-9]{0,4}) (0|[1-9][0-9]{0,9})")
_BODY: Final = re.compile(r"(?:(?:0|[1-9][0-9]{0,4}) (?:0|[1-9][0-9]{0,9})\n)*")
"""Every line after the header, at once: ``_LINE`` and a line feed, repeated."""
_MAX_FILE_BYTES: Final = 2 << 20
"""A full table (65,536 writers) is about 1.1 MB; anything over 2 MiB is not a counter file."""
_TEMP_NAME: Final = r"\.{name}\.[0-9a-f]{{12}}\.tmp"  # swarmtag._atomic's temporary file names
_SETTLED_NS: Final = 2_000_000_000
"""A file changed less than 2 s before it was read may share its identity with a later one
(coarse file-system timestamps, an inode number reused): its table is read again."""

_Identity = tuple[int, int, int, int, int]


def parse_counters(data: bytes) -> dict[int, int]:
    r"""The table writer id -> last counter in a counter file's bytes; ``ValueError`` if bad.

    Linear in the file's size: one regular expression checks every line's
    form at once, then the numbers are converted and their ranges and order
    checked in passes over lists; any other file is gone through line by
    line, to say which line is wrong (or, for CR LF line ends, to read it).

    >>> parse_counters(b"swarmtag-writer-counters-v1\n7 41\n")
    {7: 41}
    """
    try:
        text = data.decode("ascii")
    except UnicodeDecodeError:
        raise ValueError("it is not ASCII text") from None
    header, newline, body = text.partition("\n")
    if header != COUNTER_FILE_HEADER or not newline:
        raise ValueError(f"the first line is not {COUNTER_FILE_HEADER!r}")
    if body and not body.endswith("\n"):
        raise ValueError("the last line does not end in a line feed")
    if _BODY.fullmatch(body):
        numbers = [int(number) for number in body.split()]
        writers, counters = numbers[0::2], numbers[1::2]
        if (
            max(writers, default=0) <= _MAX_WRITER
            and max(counters, default=0) <= MAX_COUNTER
            and all(a < b for a, b in itertools.pairwise(writers))
        ):
            return dict(zip(writers, counters, strict=True))
    return _parse_lines(body)


def _parse_lines(body: str) -> dict[int, int]:
    """``parse_counters`` line by line (also linear): names the first bad line of ``body``."""
    table: dict[int, int] = {}
    previous = -1  # the last writer id: ids increase, so each line is checked in O(1)
    for number, line in enumerate(body.splitlines(), start=2):
        match = _LINE.fullmatch(line)
        writer, counter = (int(match[1]), int(match[2])) if match else (-1, -1)
        if not (0 <= writer <= _MAX_WRITER and 0 <= counter <= MAX_COUNTER):
            raise ValueError(f"line {number} is not '<writer id> <counter>' in range")
        if writer <= previous:
            raise ValueError(f"line {number}: writer ids are not in increasing order")
        table[writer] = counter
        previous = writer
    return table


def format_counters(table: Mapping[int, int]) -> bytes:
    r"""A counter file's bytes for ``table`` (writer id -> last counter used), sorted by id.

    >>> format_counters({12: 3, 7: 41}).decode()
    'swarmtag-writer-counters-v1\n7 41\n12 3\n'
    """
    rows = sorted(table.items())
    plain = all(type(writer) is int and type(counter) is int for writer, counter in rows)
    if not (
        plain
        and (not rows or (rows[0][0] >= 0 and rows[-1][0] <= _MAX_WRITER))
        and all(0 <= counter <= MAX_COUNTER for _writer, counter in rows)
    ):
        for writer, counter in rows:  # say which entry is wrong
            check_int("writer", writer, _MAX_WRITER)
            check_int("counter", counter, MAX_COUNTER)
    lines = [f"{COUNTER_FILE_HEADER}\n", *(f"{writer} {counter}\n" for writer, counter in rows)]
    return "".join(lines).encode("ascii")


class CounterFile:
    """The counter file of a writer's machine: ``reserve`` the next counter before sending.

    Creating one checks only the path; ``check`` reads the file (if it
    exists) and its folder, so bad input is refused before a radio is
    touched. Errors are ``CounterFileError`` naming the file.
    """

    def __init__(self, path: str | os.PathLike[str]) -> None:
        self.path = as_path(path, what="counter file path", error=CounterFileError)
        self._seen: tuple[_Identity, dict[int, int]] | None = None
        """The last table read or written, with the identity of the settled file it came from."""

    def check(self) -> Mapping[int, int]:
        """Read the table now (empty if the file does not exist yet); refuse an unusable file.

        The folder must exist and be writable, and the file, if there, must
        be a counter file: a write is never signed with a counter that cannot
        be saved first.
        """
        self._check_folder()
        return MappingProxyType(self._load())

    def last(self, writer: int) -> int | None:
        """The last counter reserved for ``writer`` (``None``: never), as the file says now."""
        return self._load().get(check_int("writer", writer, _MAX_WRITER))

    def reserve(self, writer: int) -> int:
        """The next counter of ``writer``, already saved (fsynced) as used; sign with it.

        ``FieldRangeError`` once the writer id has used its last counter
        (2**32 - 1): retire the id. Nothing is written then.
        """
        check_int("writer", writer, _MAX_WRITER)
        self._check_folder()
        with self._locked():
            table = self._load()
            last = table.get(writer, -1)
            if last >= MAX_COUNTER:
                raise FieldRangeError(
                    f"counter: writer {writer} has used its last counter ({MAX_COUNTER}); "
                    "retire this writer id and write with a new one"
                )
            table[writer] = last + 1
            data = format_counters(table)
            try:
                atomic_write_bytes(self.path, data)
                self._remember(self.path.stat(), time.time_ns(), table)
            except OSError as error:
                self._seen = None
                raise CounterFileError(
                    f"cannot save counter file {self.path}: {error.strerror or error}; "
                    "nothing was sent"
                ) from None
            return last + 1

    def _check_folder(self) -> None:
        """Refuse a missing or unwritable folder: the counter could not be saved there."""
        folder = self.path.parent
        if not os.path.isdir(folder):  # noqa: PTH112 - Path.is_dir raises ENAMETOOLONG
            raise CounterFileError(
                f"counter file {self.path}: folder {folder} does not exist (create it first)"
            )
        if not os.access(folder, os.W_OK | os.X_OK):
            raise CounterFileError(
                f"counter file {self.path}: folder {folder} is not writable; "
                "give a --counter-file in a folder this user may write"
            )

    def _remember(self, info: os.stat_result, read_ns: int, table: dict[int, int]) -> None:
        """Keep ``table`` for the file ``info`` describes if it had settled at ``read_ns``."""
        identity = (info.st_dev, info.st_ino, info.st_size, info.st_mtime_ns, info.st_ctime_ns)
        settled = max(info.st_mtime_ns, info.st_ctime_ns) <= read_ns - _SETTLED_NS
        self._seen = (identity, dict(table)) if settled else None

    def _load(self) -> dict[int, int]:
        """The table in the file now (a copy), or an empty one if there is no file yet.

        The file is read only if it is not the settled file read last time.
        """
        try:
            fd = os.open(self.path, os.O_RDONLY | getattr(os, "O_NONBLOCK", 0))  # no FIFO hang
        except FileNotFoundError:
            return {}
        except IsADirectoryError:
            raise self._folder() from None
        except OSError as error:
            raise CounterFileError(
                f"cannot read counter file {self.path}: {error.strerror or error}"
            ) from None
        try:
            info = os.fstat(fd)
            if stat.S_ISDIR(info.st_mode):
                raise self._folder()
            if not stat.S_ISREG(info.st_mode):
                raise CounterFileError(f"counter file {self.path} is not a regular file")
            identity = (info.st_dev, info.st_ino, info.st_size, info.st_mtime_ns, info.st_ctime_ns)
            if self._seen is not None and self._seen[0] == identity:
                return dict(self._seen[1])
            read_ns = time.time_ns()
            data = os.read(fd, _MAX_FILE_BYTES + 1)
            if len(data) > _MAX_FILE_BYTES:
                raise CounterFileError(f"counter file {self.path} is too large to be one")
        except OSError as error:
            raise CounterFileError(
                f"cannot read counter file {self.path}: {error.strerror or error}"
            ) from None
        finally:
            os.close(fd)
        try:
            table = parse_counters(data)
        except ValueError as error:
            raise CounterFileError(
                f"{self.path} is not a swarmtag counter file ({error}); give another "
                "--counter-file, or move this one away (a new file starts each writer at 0)"
            ) from None
        self._remember(info, read_ns, table)
        return table

    def _folder(self) -> CounterFileError:
        return CounterFileError(
            f"counter file {self.path} is a folder; give the file's path inside it, "
            f"e.g. {self.path / 'writer.counters'}"
        )

    @contextmanager
    def _locked(self) -> Iterator[None]:
        """Hold an exclusive lock on the folder (POSIX) and clear stale temporaries under it."""
        folder = self.path.parent
        fd = -1
        try:
            if fcntl is not None:
                fd = os.open(folder, os.O_RDONLY)
                fcntl.flock(fd, fcntl.LOCK_EX)  # released when fd is closed
            self._remove_stale_temporaries(folder)
        except OSError as error:
            if fd >= 0:
                os.close(fd)
            raise CounterFileError(
                f"cannot lock the folder of counter file {self.path}: {error.strerror or error}"
            ) from None
        try:
            yield
        finally:
            if fd >= 0:
                os.close(fd)

    def _remove_stale_temporaries(self, folder: Path) -> None:
        """Delete temporaries a killed save of this file left (no one else saves it now)."""
        pattern = re.compile(_TEMP_NAME.format(name=re.escape(self.path.name)))
        for entry in folder.iterdir():
            if pattern.fullmatch(entry.name) and not entry.is_symlink() and entry.is_file():
                entry.unlink(missing_ok=True)
