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
  against 0.2 ns without). Only ``counted`` entry points, which allocate
  (the scene sampler's grids), keep it.
- a call that is not inlined copies every array descriptor of those tuples
  (about 7 KB): the kernel ran 3 times slower with its phases as real calls.
  So every function that takes the state is ``inlined`` (LLVM's
  ``alwaysinline``; numba's own inliner gave the same speed but compiled for
  2.5 minutes instead of 1.5): a tick is one function. Leaves that take only
  numbers are plain ``jit``.

And two that shape the first compilation (measured on one core, the entry
point of batched runs and then the split kernels: 529 s and 138 s before, 131 s
and 51 s after):

- only the entry points (``entry``, ``counted``) get numba's Python and C
  wrappers; each wrapper unpacks every array of the state's tuples, and
  making them for every inner function was most of the compile time
  (``jit`` and ``inlined`` functions refuse calls from Python);
- constants passed as arguments are widened from literals, so a function
  is compiled once per argument type (``emit`` had been compiled ten times,
  once per event kind).

Last, every function numba compiles is optimised and turned into machine code on
its own, with everything it inlines: a function of calls only, one level
above big phases, would compile the tick once more for nothing. Such a
function with one caller is ``glue``, copied into that caller by numba's
own inliner (``_tick.tick_run``, ``tick_robots`` and two of ``_split``'s;
compiled on their own they would add about 10 s to the batched entry
point's first compilation and 6 s to the split kernels', for no faster
kernel). Gluing the tick's settle and collision phases too makes runs of
3 robots 15 % slower; they stay ``inlined``.
"""

from __future__ import annotations

import contextlib
import hashlib
import os
from collections.abc import Callable
from pathlib import Path
from typing import Any, Final, TypeVar

import numba
from numba.core import sigutils, types
from numba.core.registry import CPUDispatcher

from swarmtag._sources import imported_sources

__all__ = ["counted", "discard_stale_machine_code", "entry", "glue", "inlined", "jit"]

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


_INTERNAL: dict[str, Any] = {"no_cpython_wrapper": True, "no_cfunc_wrapper": True}
"""Options of functions that only compiled code calls: no Python or C wrapper.

Each wrapper unpacks every array of the state's tuples (hundreds of
arguments): generating and compiling those wrappers for every inner
function was most of the kernel's first compilation.
"""


class _CompiledOnly(CPUDispatcher):
    """A dispatcher without a Python wrapper: a call from Python raises instead of crashing.

    numba would jump to the missing wrapper's null address; calls from
    compiled code are typed and linked without ever reaching ``__call__``.
    """

    def __call__(self, *args: object, **kwargs: object) -> None:
        msg = (
            f"{self.py_func.__qualname__} is compiled for calls from compiled code only; "
            "Python calls the kernel through its entry points"
        )
        raise TypeError(msg)


_normalize: Callable[[object], tuple[tuple[object, ...], Any]] = sigutils.normalize_signature
_unliteral: Callable[[object], object] = types.unliteral


def _compiled(function: _F, options: dict[str, Any], *, python_calls: bool) -> _F:
    """``function`` compiled with ``options``, once per argument type.

    numba types a module constant passed as an argument (an event kind, a
    flag) as a literal and compiles the callee again for every value;
    folding the constant in is LLVM's work once the callee is inlined, so
    the literals are widened to their plain types before compiling. Without
    ``python_calls`` the dispatcher refuses calls from Python (``_CompiledOnly``).
    """
    dispatcher: Any = _njit(**options)(function)
    compile_literal: Callable[[object], object] = dispatcher.compile

    def compile_plain(signature: object) -> object:
        arguments, result = _normalize(signature)
        plain = tuple(_unliteral(argument) for argument in arguments)
        return compile_literal(plain if result is None else result(*plain))

    dispatcher.compile = compile_plain
    if not python_calls:
        dispatcher.__class__ = _CompiledOnly
    compiled: _F = dispatcher
    return compiled


def jit(function: _F) -> _F:
    """Compile a kernel function that compiled code calls: nopython, cached, IEEE, no GIL.

    No reference counts and no Python wrapper; it must allocate nothing (no
    new arrays, lists or objects).
    """
    return _compiled(function, {**_OPTIONS, **_INTERNAL, "_nrt": False}, python_calls=False)


def entry(function: _F) -> _F:
    """Like ``jit``, callable from Python (the runner's calls into the kernel)."""
    return _compiled(function, {**_OPTIONS, "_nrt": False}, python_calls=True)


def inlined(function: _F) -> _F:
    """Like ``jit``, and always inlined into its callers (functions that take the state)."""
    options = {**_OPTIONS, **_INTERNAL, "_nrt": False, "forceinline": True}
    return _compiled(function, options, python_calls=False)


def glue(function: _F) -> _F:
    """A function of calls only, copied into its one caller by numba: never compiled alone.

    Its caller's compilation types and lowers the copy; the function gets
    no machine code of its own (see the module's notes for where it pays).
    """
    options = {**_OPTIONS, **_INTERNAL, "_nrt": False, "inline": "always"}
    return _compiled(function, options, python_calls=False)


def counted(function: _F) -> _F:
    """An entry point with numba's reference counting on (it allocates arrays, takes views)."""
    return _compiled(function, _OPTIONS, python_calls=True)


_DATA_SUFFIXES: Final = (".npz", ".npy")
"""Package data beside the sources whose numbers the compiled code holds (``ziggurat.npz``)."""


def _kernel_sources() -> list[Path]:
    """This package's sources and data, and the project modules they import directly.

    The compiled functions read constants (robot modes, event kinds, tag
    statuses, shared rules) from modules outside this folder, and tables
    from data files in it (``_DATA_SUFFIXES``: numba freezes a global array
    into the machine code): an edit there must discard the machine code too.
    """
    here = Path(__file__).parent
    sources = imported_sources(here.glob("*.py"), transitive=False)
    data = (path for path in here.iterdir() if path.suffix in _DATA_SUFFIXES)
    return sorted({*sources, *data})


def _sources_digest() -> str:
    """SHA-256 over the kernel's sources and data (paths and bytes, in path order)."""
    digest = hashlib.sha256()
    root = Path(__file__).parents[2]
    for path in _kernel_sources():
        name = path.relative_to(root).as_posix()
        digest.update(name.encode() + b"\0" + path.read_bytes() + b"\0")
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
