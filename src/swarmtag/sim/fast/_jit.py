"""The numba decorators of the compiled kernel: cached, IEEE arithmetic, no GIL, no refcounts.

``fastmath`` stays off so that every ``+``, ``*``, ``/`` and ``sqrt`` is one
correctly rounded IEEE operation, as in numpy (no contraction into FMA, no
reassociation): that is what lets the compiled kernel match the reference bit
for bit. ``cache=True`` keeps the machine code beside the sources, so a second
process starts without compiling; ``nogil=True`` lets several Python threads
run kernels at once (the backend's parallelism over runs).

Two measured costs shape the rest:

- numba's reference counting is off (``_nrt=False``): the kernel's functions
  take the state as tuples of about a hundred arrays and allocate nothing;
  with it on, every call of a function with more than one branch increfs and
  decrefs every array of every tuple (atomic operations: about 260 ns a call
  against 0.2 ns without). Only ``counted`` entry points, which pick each
  run's generators out of typed lists, keep it.
- a call that is not inlined copies every array descriptor of those tuples
  (about 7 KB): the kernel ran 3 times slower with its phases as real calls.
  So every function that takes the state is ``inlined`` (LLVM's
  ``alwaysinline``; numba's own inliner gave the same speed but compiled for
  2.5 minutes instead of 1.5): a tick is one function. Leaves that take only
  numbers are plain ``jit``.
"""

from __future__ import annotations

import contextlib
import hashlib
import os
from collections.abc import Callable
from pathlib import Path
from typing import Any, Final, TypeVar

import numba

__all__ = ["counted", "discard_stale_machine_code", "inlined", "jit"]

_STAMP: Final = "swarmtag-kernel-sources.sha256"
"""File beside the cached machine code: the digest of the sources it was compiled from."""

_F = TypeVar("_F", bound=Callable[..., Any])

_njit: Any = numba.njit  # ``_nrt`` is not in numba's typed signature of njit
_OPTIONS: dict[str, Any] = {
    "cache": True,
    "fastmath": False,
    "error_model": "numpy",
    "nogil": True,
}


def jit(function: _F) -> _F:
    """Compile a kernel function: nopython, cached, IEEE arithmetic, no GIL, no refcounts.

    It must allocate nothing (no new arrays, lists or objects).
    """
    compiled: _F = _njit(**_OPTIONS, _nrt=False)(function)
    return compiled


def inlined(function: _F) -> _F:
    """Like ``jit``, and always inlined into its callers (functions that take the state)."""
    compiled: _F = _njit(**_OPTIONS, _nrt=False, forceinline=True)(function)
    return compiled


def counted(function: _F) -> _F:
    """Like ``jit`` with numba's reference counting on (typed lists, array views)."""
    compiled: _F = _njit(**_OPTIONS)(function)
    return compiled


def _sources_digest() -> str:
    """SHA-256 over this package's Python sources (names and bytes, in name order)."""
    digest = hashlib.sha256()
    for path in sorted(Path(__file__).parent.glob("*.py")):
        digest.update(path.name.encode() + b"\0" + path.read_bytes() + b"\0")
    return digest.hexdigest()


def discard_stale_machine_code(entry: object) -> None:
    """Delete cached machine code compiled from other sources than this package's now.

    numba checks a cached function against its own file only, but the
    kernel's entry points inline functions from every module of the package:
    after an edit to ``_sense.py`` alone, ``_tick.advance`` would load machine
    code built from the old ``_sense.py``. So the cache folder (the one
    numba chose for ``entry``) carries the digest of all the sources, and
    when it differs every cached file there goes and is compiled again. A
    folder that cannot be written is left alone (numba cannot cache there
    either).
    """
    folder = getattr(getattr(entry, "_cache", None), "_cache_path", None)
    if not isinstance(folder, str) or not Path(folder).is_dir():
        return
    stamp = Path(folder) / _STAMP
    current = _sources_digest()
    with contextlib.suppress(OSError):
        if stamp.read_text(encoding="ascii") == current:
            return
    try:
        for cached in Path(folder).iterdir():
            if cached.suffix in (".nbi", ".nbc"):
                cached.unlink(missing_ok=True)
        temporary = stamp.with_suffix(f".{os.getpid()}.tmp")
        temporary.write_text(current, encoding="ascii")
        temporary.replace(stamp)
    except OSError:
        return
