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

from collections.abc import Callable
from typing import Any, TypeVar

import numba

__all__ = ["counted", "inlined", "jit"]

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
