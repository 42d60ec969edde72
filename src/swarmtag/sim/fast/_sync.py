"""Threads that meet inside compiled code: atomic integers and a spinning barrier.

A large run's tick is split over threads phase by phase (``_split``). Handing
each phase to a thread through Python's pool cost about 0.1 ms a hand-over
and each entry call about 20-40 µs (numba unpacks the state's tuples), a
quarter of a 20,000-robot tick; here every thread runs a whole call of ticks
and the threads wait for each other at ``barrier`` (a few µs). numba has no
atomic operations, so they are LLVM's, emitted by ``numba.extending.intrinsic``
on one ``int64`` entry of an array (``sync``, laid out by the ``SYNC_*``
indices, one cache line apart). Sequentially consistent atomics also order
the plain loads and stores around them: what one thread wrote before the
barrier, the others read after it.
"""

# numba's intrinsic and code-generation interfaces are untyped: their arguments are Any here.
# ruff: noqa: ANN401

from __future__ import annotations

import sys
from typing import Any, Final

import numpy as np
from llvmlite import ir  # type: ignore[import-untyped]
from numba import types
from numba.core import cgutils
from numba.extending import intrinsic

from swarmtag.sim.fast._jit import jit

__all__ = [
    "SYNC_ABORT",
    "SYNC_LINE",
    "SYNC_SIZE",
    "SYNC_VALUES",
    "arrive",
    "atomic_add",
    "atomic_load",
    "atomic_store",
    "barrier",
    "passed",
    "pause",
    "sync_array",
]

SYNC_LINE: Final = 8
"""int64 entries of a cache line: each counter on its own line."""
SYNC_ARRIVED: Final = 0
"""Threads at the barrier now."""
SYNC_ROUND: Final = 1 * SYNC_LINE
"""Barriers passed: a waiting thread spins until it changes."""
SYNC_ABORT: Final = 2 * SYNC_LINE
"""Non-zero: a thread will not come (its caller failed); waiting threads return False."""
SYNC_VALUES: Final = 3 * SYNC_LINE
"""First of the entries the threads pass each other values in (``_split``; two lines)."""
SYNC_SIZE: Final = 5 * SYNC_LINE

_SPINS: Final = 256
"""Spins before a waiting thread gives its core up on each further check (more threads
than free cores: the thread it waits for may need that core)."""
_get_item_pointer: Any = cgutils.get_item_pointer
_YIELD: Final = "SwitchToThread" if sys.platform == "win32" else "sched_yield"


def sync_array() -> np.ndarray:
    """A fresh ``sync`` array: nobody at the barrier, no round passed, no abort."""
    return np.zeros(SYNC_SIZE, dtype=np.int64)


def _entry_pointer(context: Any, builder: Any, signature: Any, args: Any) -> Any:
    """LLVM pointer to ``array[index]`` (the first two arguments)."""
    array_type = signature.args[0]
    array = context.make_array(array_type)(context, builder, args[0])
    return _get_item_pointer(context, builder, array_type, array, [args[1]])


def _check_int64_array(array: Any) -> None:
    if not (isinstance(array, types.Array) and array.dtype == types.int64 and array.ndim == 1):
        msg = f"atomics need a 1-D int64 array, not {array}"
        raise TypeError(msg)


def _atomic_add_typed(_typing: Any, array: Any, index: Any, value: Any) -> Any:
    """``array[index] += value`` at once for every thread; returns the value before."""
    _check_int64_array(array)

    def codegen(context: Any, builder: Any, signature: Any, args: Any) -> Any:
        pointer = _entry_pointer(context, builder, signature, args)
        return builder.atomic_rmw("add", pointer, args[2], "seq_cst")

    return types.int64(array, types.intp, types.int64), codegen


def _atomic_load_typed(_typing: Any, array: Any, index: Any) -> Any:
    """``array[index]``, read as one atomic operation (never cached in a register)."""
    _check_int64_array(array)

    def codegen(context: Any, builder: Any, signature: Any, args: Any) -> Any:
        pointer = _entry_pointer(context, builder, signature, args)
        return builder.load_atomic(pointer, "seq_cst", 8)

    return types.int64(array, types.intp), codegen


def _atomic_store_typed(_typing: Any, array: Any, index: Any, value: Any) -> Any:
    """``array[index] = value`` as one atomic operation."""
    _check_int64_array(array)

    def codegen(context: Any, builder: Any, signature: Any, args: Any) -> Any:
        pointer = _entry_pointer(context, builder, signature, args)
        builder.store_atomic(args[2], pointer, "seq_cst", 8)
        return context.get_dummy_value()

    return types.void(array, types.intp, types.int64), codegen


def _yield_core_typed(_typing: Any) -> Any:
    """Let the operating system run another thread on this core (``sched_yield``)."""

    def codegen(context: Any, builder: Any, _signature: Any, _args: Any) -> Any:
        function_type = ir.FunctionType(ir.IntType(32), [])
        function = _get_or_insert_function(builder.module, function_type, _YIELD)
        builder.call(function, [])
        return context.get_dummy_value()

    return types.void(), codegen


# Typed by numba when compiled code calls them; to mypy they are untyped objects.
atomic_add: Any = intrinsic(_atomic_add_typed)
atomic_load: Any = intrinsic(_atomic_load_typed)
atomic_store: Any = intrinsic(_atomic_store_typed)
_yield_core: Any = intrinsic(_yield_core_typed)
_get_or_insert_function: Any = cgutils.get_or_insert_function


@jit
def arrive(sync: np.ndarray, parts: int) -> int:
    """Arrive at the barrier of ``parts`` threads: the round to wait out, or -1 if all are here.

    The last to arrive resets the count and starts the next round, which
    releases the others.
    """
    round_now: int = atomic_load(sync, SYNC_ROUND)
    if atomic_add(sync, SYNC_ARRIVED, 1) == parts - 1:
        atomic_store(sync, SYNC_ARRIVED, 0)
        atomic_add(sync, SYNC_ROUND, 1)
        return -1
    return round_now


@jit
def passed(sync: np.ndarray, round_now: int) -> int:
    """1 once round ``round_now`` (``arrive``'s) has passed, 0 while not, -1 on ``SYNC_ABORT``."""
    if round_now < 0 or atomic_load(sync, SYNC_ROUND) != round_now:
        return 1
    if atomic_load(sync, SYNC_ABORT) != 0:
        return -1
    return 0


@jit
def pause(spins: int) -> int:
    """One more spin of a waiting thread (``spins`` so far); past ``_SPINS`` it yields its core."""
    if spins >= _SPINS:
        _yield_core()
    return spins + 1


@jit
def barrier(sync: np.ndarray, parts: int) -> bool:
    """Wait until all ``parts`` threads have arrived; False if one will not (``SYNC_ABORT``).

    Every thread's writes before the barrier are seen by every thread after it.
    """
    round_now = arrive(sync, parts)
    spins = 0
    state = passed(sync, round_now)
    while state == 0:
        spins = pause(spins)
        state = passed(sync, round_now)
    return state > 0
