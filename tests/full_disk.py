"""A real full disk for tests: a small tmpfs mounted for one test, filled to the last byte.

Mounting needs root (CI and the development machine run the suite as root);
elsewhere the tests that need it are skipped with the reason.
"""

from __future__ import annotations

import contextlib
import errno
import os
import subprocess
from collections.abc import Iterator
from pathlib import Path

import pytest

REFUSALS = [
    (errno.ENOSPC, "no space left on device"),
    (errno.EDQUOT, "disk quota exceeded"),
    (errno.EROFS, "read-only file system"),
    (errno.EFBIG, "file too large"),
    (errno.EIO, "input/output error"),
]
"""What a device refuses a write with, and the words the message must use for each."""

FILLER = ".filler"
"""The file that takes the last free bytes of a mounted tmpfs."""


@contextlib.contextmanager
def tmpfs(folder: Path, size: str = "4m") -> Iterator[Path]:
    """Mount a tmpfs of ``size`` on ``folder`` for the block; skip the test where one cannot."""
    if os.geteuid() != 0:
        pytest.skip("mounting a tmpfs (a real full disk) needs root")
    folder.mkdir(parents=True, exist_ok=True)
    mounted = subprocess.run(
        ["mount", "-t", "tmpfs", "-o", f"size={size}", "tmpfs", str(folder)],
        capture_output=True,
        text=True,
        check=False,
    )
    if mounted.returncode != 0:
        pytest.skip(f"mount -t tmpfs is not permitted here: {mounted.stderr.strip()}")
    try:
        yield folder
    finally:
        subprocess.run(["umount", "-l", str(folder)], capture_output=True, check=False)


def fill(folder: Path) -> None:
    """Take every free byte of ``folder``'s device with ``folder/.filler``."""
    block = b"\0" * 4096
    with (folder / FILLER).open("ab", buffering=0) as handle:
        try:
            while True:
                handle.write(block)
        except OSError as problem:
            if problem.errno != errno.ENOSPC:
                raise


def free(folder: Path) -> None:
    """Give the space back."""
    (folder / FILLER).unlink()
