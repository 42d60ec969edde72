"""The numba decorators of the compiled kernel: cached, no fast-math, no GIL, no reference counts.

``fastmath`` stays off so that every ``+``, ``*``, ``/`` and ``sqrt`` is one
correctly rounded IEEE operation, as in numpy (no contraction into FMA, no
reassociation): that is what lets the compiled kernel match the reference bit
for bit. ``cache=True`` keeps the machine code beside the sources, so a second
process starts without compiling; ``nogil=True`` lets several Python threads
run kernels at once (the backend's parallelism over runs).

``jit`` also turns numba's reference counting off (``_nrt=False``). The
kernel's functions take the state as tuples of some eighty arrays and
allocate nothing; with reference counting on, every call of a function with
more than one branch increfs and decrefs every array of every tuple (atomic
operations, measured at about 260 ns a call against 0.2 ns without), which
made the kernel as slow as numpy. Only ``counted``, the entry point that
picks each run's generators out of typed lists, keeps it.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any, TypeVar

import numba

__all__ = ["counted", "inlined", "jit"]

_F = TypeVar("_F", bound=Callable[..., Any])

_njit: Any = numba.njit  # ``_nrt`` is not in numba's typed signature of njit


def jit(function: _F) -> _F:
    """Compile a kernel function: nopython, cached, IEEE arithmetic, no GIL, no refcounts.

    It must allocate nothing (no new arrays, lists or objects).
    """
    compiled: _F = _njit(cache=True, fastmath=False, error_model="numpy", nogil=True, _nrt=False)(
        function
    )
    return compiled


def inlined(function: _F) -> _F:
    """Like ``jit``, inlined into its callers by numba (small helpers called per pair)."""
    compiled: _F = _njit(
        cache=True, fastmath=False, error_model="numpy", nogil=True, _nrt=False, inline="always"
    )(function)
    return compiled


def counted(function: _F) -> _F:
    """Like ``jit`` with numba's reference counting on (typed lists, array views)."""
    compiled: _F = _njit(cache=True, fastmath=False, error_model="numpy", nogil=True)(function)
    return compiled
