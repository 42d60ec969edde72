"""Every output of a command: checked before any work, written aside, moved into place together.

One rule for all commands: a file output's folder must already exist (a
mistyped folder is an error, never a new folder); the path must not be a
folder or a special file; the folder must be writable (tested by creating
the staging folder there, so it also holds for root and read-only mounts);
no two outputs, and no output and input, may be the same file. A folder
output (``--figures DIR``) may be created, but its parent must exist.

Work writes each output under a hidden staging folder beside its target,
with the target's own name (so formats chosen by suffix still work). Only
when every output was written are they moved into place, with Ctrl-C held
back for those few renames; any failure or Ctrl-C before that removes the
staging folders and leaves the targets exactly as they were. A write the
device refuses (full, over quota, read-only, an I/O error) is one
``WriteFailure`` naming the target, never the staged file:
``no space left on device while writing out/report.html``. Their removal
holds Ctrl-C back too, and a staging folder that a Ctrl-C between two steps
kept from its removal (one arriving as the ``with`` block ends, before the
context manager runs) is removed when the process exits.

>>> import tempfile, pathlib
>>> folder = pathlib.Path(tempfile.mkdtemp())
>>> plan = OutputPlan()
>>> target = plan.file("--out", folder / "a.txt", suffixes=(".txt",))
>>> with plan.writing() as stage:
...     _ = stage.path(target).write_text("hello")
>>> (folder / "a.txt").read_text(), sorted(p.name for p in folder.iterdir())
('hello', ['a.txt'])
"""

from __future__ import annotations

import atexit
import os
import secrets
import shutil
import stat
from collections.abc import Iterator, Sequence
from contextlib import contextmanager
from pathlib import Path
from typing import NoReturn

from swarmtag._atomic import WriteFailure, failures_named, write_failure
from swarmtag._interrupt import checkpoint, deferred
from swarmtag.errors import OutputError, SwarmtagError

__all__ = ["STAGING_PREFIX", "OutputPlan", "Stage"]

STAGING_PREFIX = ".swarmtag-staging-"
"""Name prefix of the hidden staging folders (removed on failure; left only by SIGKILL)."""

_unremoved: set[Path] = set()
"""Staging folders made by this process and not yet removed (the exit's backstop)."""


def _remove(roots: Sequence[Path]) -> None:
    """Remove staging folders, with Ctrl-C held back until they are gone."""
    with deferred():
        for root in roots:
            shutil.rmtree(root, ignore_errors=True)
            _unremoved.discard(root)


@atexit.register
def _remove_unremoved() -> None:
    """At exit, remove what an ill-timed Ctrl-C kept ``writing()`` from removing."""
    _remove(sorted(_unremoved))


def _key(path: Path) -> str:
    """One spelling per file: the real folder plus the name (the file itself may not exist).

    A path without a name of its own (``.``, ``..``, ``/``) is an existing folder: its real path.
    """
    if path.name in ("", ".."):
        return os.path.realpath(path)
    return str(Path(os.path.realpath(path.parent)) / path.name)


class Stage:
    """Where a command writes its outputs while it works: ``stage.path(target)``."""

    def __init__(self, staged: dict[str, Path], targets: dict[str, Path]) -> None:
        self._staged = staged
        self._targets = targets
        self.last: Path | None = None
        """The target last asked for: the one being written when a write names no file."""

    def path(self, target: Path) -> Path:
        """The staged path to write instead of ``target`` (a planned file or folder output)."""
        try:
            staged = self._staged[_key(target)]
        except KeyError:
            msg = f"{target}: not a planned output"  # a bug in the command, not bad input
            raise OutputError(msg) from None
        self.last = self._targets[_key(target)]
        return staged

    def target(self, written: object) -> Path | None:
        """The target a staged path stands for (a file in a staged folder: that file's target).

        A path in a staging folder that is no planned output (a library's
        scratch file) stands for the target last asked for; a path outside
        the staging folders, for itself; no path at all, for the last target.
        """
        if not isinstance(written, (str, bytes, os.PathLike)):  # a descriptor, or no file at all
            return self.last
        given = Path(os.fsdecode(written))
        where = given.resolve()
        for key, staged in self._staged.items():
            home = staged.resolve()
            if where == home or home in where.parents:
                return self._targets[key] / where.relative_to(home)
        if any(part.startswith(STAGING_PREFIX) for part in where.parts):
            return self.last
        return given

    def rename(self, error: SwarmtagError) -> SwarmtagError:
        """``error`` with every staged path in its message spelled as its target."""
        if isinstance(error, WriteFailure):
            target = self.target(error.path)
            return error if target is None else WriteFailure(error.reason, target)
        message = str(error)
        # Longest first, so that a staged folder's file is not renamed by its folder's prefix.
        for key, staged in sorted(self._staged.items(), key=lambda item: -len(str(item[1]))):
            message = message.replace(str(staged), str(self._targets[key]))
        if message != str(error):
            error.args = (message,)
        return error


class OutputPlan:
    """The outputs of one command, checked when added, written by ``writing()``."""

    def __init__(self, *, error: type[SwarmtagError] = OutputError) -> None:
        self._error = error
        self._files: dict[str, tuple[str, Path]] = {}
        self._folders: dict[str, tuple[str, Path]] = {}
        self._inputs: dict[str, tuple[str, Path]] = {}

    def _fail(self, option: str, path: Path, reason: str) -> NoReturn:
        msg = f"{option}: {str(path)!r} {reason}"
        raise self._error(msg)

    def _mode(self, option: str, path: Path, checked: Path) -> int | None:
        """The file mode of ``checked`` (``path`` or its folder); None if there is none."""
        try:
            return checked.stat().st_mode
        except FileNotFoundError:
            return None
        except OSError as problem:  # a name too long, a loop of links, a file as a folder
            self._fail(option, path, f"cannot be checked ({problem.strerror})")

    def _claim(self, option: str, path: Path) -> str:
        """Refuse a path already named by another output or an input; else its key."""
        key = _key(path)
        for table in (self._files, self._folders, self._inputs):
            if key in table:
                other, _ = table[key]
                what = "an input" if table is self._inputs else "an output"
                self._fail(option, path, f"is also {what} ({other}); give each its own file")
        return key

    def _check_folder(self, option: str, path: Path, folder: Path) -> None:
        mode = self._mode(option, path, folder)
        if mode is None or not stat.S_ISDIR(mode):
            reason = "does not exist" if mode is None else "is not a folder"
            self._fail(option, path, f"cannot be written: folder {str(folder)!r} {reason}")

    def input(self, option: str, path: Path) -> None:
        """Note an input file, so that no output overwrites it."""
        self._inputs[_key(path)] = (option, path)

    def appended(self, option: str, path: Path) -> None:
        """Note a file read and appended to while the command works (a cache; not staged).

        It may be no other input and no output.
        """
        self._inputs[self._claim(option, path)] = (option, path)

    def file(self, option: str, path: Path, *, suffixes: Sequence[str] = ()) -> Path:
        """Plan the file ``path`` for ``option``; refuse it now if it could not be written."""
        if "\0" in str(path) or not str(path):
            self._fail(option, path, "is not a valid path")
        if suffixes and path.suffix.lower() not in suffixes:
            self._fail(option, path, f"must end in {' or '.join(suffixes)}")
        self._check_folder(option, path, path.parent)
        mode = self._mode(option, path, path)
        if mode is not None and stat.S_ISDIR(mode):
            self._fail(option, path, "is a folder; give a file name")
        if mode is not None and not stat.S_ISREG(mode):
            self._fail(option, path, "is not a regular file (a FIFO, socket or device)")
        self._files[self._claim(option, path)] = (option, path)
        return path

    def folder(self, option: str, path: Path) -> Path:
        """Plan the folder ``path`` (created if missing; its parent must exist)."""
        if "\0" in str(path) or not str(path):
            self._fail(option, path, "is not a valid path")
        if path.name in ("", ".."):  # "." or "..": staged beside it, under its real name
            path = Path(os.path.realpath(path))
            if not path.name:
                self._fail(option, path, "cannot be written (the root folder)")
        mode = self._mode(option, path, path)
        if mode is not None and not stat.S_ISDIR(mode):
            self._fail(option, path, "is a file; give a folder")
        if mode is None:
            self._check_folder(option, path, path.parent)
        self._folders[self._claim(option, path)] = (option, path)
        return path

    def _staging_root(self, option: str, path: Path, folder: Path, roots: dict[str, Path]) -> Path:
        """A new staging folder in ``folder``, noted in ``roots`` first (so Ctrl-C removes it)."""
        root = folder / f"{STAGING_PREFIX}{secrets.token_hex(6)}"
        roots[os.path.realpath(folder)] = root
        _unremoved.add(root)
        try:
            root.mkdir()
        except OSError as problem:
            reason = problem.strerror or "not writable"
            self._fail(option, path, f"cannot be written in folder {str(folder)!r} ({reason})")
        return root

    @contextmanager
    def writing(self) -> Iterator[Stage]:
        """Stage every output; move all into place if the body succeeds, else remove them all."""
        roots: dict[str, Path] = {}
        staged: dict[str, Path] = {}
        targets: dict[str, Path] = {}
        moves: list[tuple[Path, Path, bool]] = []
        stage = Stage(staged, targets)
        try:
            planned = [(k, v, False) for k, v in self._files.items()]
            planned += [(k, v, True) for k, v in self._folders.items()]
            for key, (option, path), is_folder in planned:
                where = os.path.realpath(path.parent)
                if where not in roots:
                    self._staging_root(option, path, path.parent, roots)
                temp = roots[where] / path.name
                if is_folder:
                    temp.mkdir()
                staged[key] = temp
                targets[key] = path
                moves.append((temp, path, is_folder))
            try:
                yield stage
            except OSError as problem:  # written by a library straight to the staged file
                written = problem.path if isinstance(problem, WriteFailure) else problem.filename
                named = stage.target(written)
                everything = ", ".join(str(target) for target in targets.values())
                failure = write_failure(problem, named or everything)
                if failure is None or not (named or everything):
                    raise
                raise failure from None
            except SwarmtagError as error:
                renamed = stage.rename(_device_failure(error) or error)
                if renamed is error:
                    raise
                raise renamed from None
            missing = [str(target) for temp, target, _ in moves if not temp.exists()]
            if missing:  # a command that planned an output must write it
                msg = f"not written: {', '.join(missing)}"
                raise self._error(msg)
            checkpoint()  # a Ctrl-C some library swallowed: what was computed since is not kept
            _commit(moves)
        finally:
            _remove([*roots.values()])


def _device_failure(error: BaseException) -> WriteFailure | None:
    """The ``WriteFailure`` behind ``error`` (a writer that wrapped it in its own error), if any."""
    seen: BaseException | None = error
    for _ in range(8):  # a chain of a few wrappers at most
        if seen is None or isinstance(seen, WriteFailure):
            return seen
        seen = seen.__cause__ or seen.__context__
    return None


def _commit(moves: Sequence[tuple[Path, Path, bool]]) -> None:
    """Move the staged outputs into place with Ctrl-C held back until all are there."""
    with deferred():
        for temp, target, is_folder in moves:
            with failures_named(target):
                if not is_folder:
                    temp.replace(target)
                    continue
                target.mkdir(exist_ok=True)
                for item in sorted(temp.rglob("*")):  # merged file by file into what is there
                    destination = target / item.relative_to(temp)
                    if item.is_dir():
                        destination.mkdir(exist_ok=True)
                    else:
                        item.replace(destination)
