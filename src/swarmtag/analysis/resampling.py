"""Vectorised resampling of whole runs: multiplicities, re-pooled percentiles, seeded streams.

A bootstrap resample of ``R`` runs is represented by how often each run was
drawn (a row of multiplicities summing to ``R``). Means over resampled runs
are then a matrix product, and percentiles of re-pooled latencies are
weighted order statistics: with the condition's latencies sorted once, the
element at position ``i`` of a resample's (virtual) sorted sample is the
first latency whose cumulative multiplicity exceeds ``i``. The result equals
``np.percentile`` of the explicitly concatenated resample, bit for bit.

Each condition draws from its own generator, keyed by a digest of its name
(not its position among the conditions present), so adding or removing a
condition never changes another condition's resamples.

Resamples are drawn and evaluated in chunks of at most ``CHUNK_ELEMENTS``
(resamples x values) so no ``resamples x runs`` array ever exists; only the
``B`` bootstrap values of each figure are kept. The draws do not depend on
the chunking: ``Generator.integers`` with its default ``int64`` dtype takes
every value from one continuing stream (for ``int64``/``int32`` and unsigned
alike; only the 8- and 16-bit dtypes buffer within one call, so they must not
be used here). Sums over the resampled runs are BLAS matrix products, whose
last bits can depend on how many rows one product has: the chunk geometry
(``CHUNK_ELEMENTS`` and the rows-per-chunk rule of ``iter_multiplicities``)
is therefore part of the numeric results and must not change.
``bootstrap_memory`` estimates what a bootstrap needs so that callers can
refuse it (``swarmtag._resources.check_memory``) before anything is drawn.
"""

from __future__ import annotations

import hashlib
from collections.abc import Iterator, Sequence
from contextlib import contextmanager
from functools import cache
from typing import Any, Final

import numpy as np
from numpy.typing import NDArray

from swarmtag._checks import MAX_SEED, check_int, check_text
from swarmtag._interrupt import checkpoint
from swarmtag.analysis._kernels import PERCENTILE_ROWS, count_draws, weighted_percentiles
from swarmtag.analysis.alignment import CURVE_THRESHOLDS
from swarmtag.analysis.curves import LATENCY_PERCENTILES
from swarmtag.analysis.kpis import METRICS, OPTIONAL_METRICS
from swarmtag.errors import StatisticsError

__all__ = [
    "CHUNK_ELEMENTS",
    "PERCENTILE_ROWS",
    "PER_VALUE_ARRAYS",
    "ROW_VALUES",
    "THREAD_BYTES",
    "WORKING_ARRAYS",
    "bootstrap_memory",
    "condition_generator",
    "condition_seed_sequence",
    "iter_multiplicities",
    "multiplicities",
    "one_blas_thread",
    "resampled_percentiles",
]

CHUNK_ELEMENTS: Final = 1 << 22
"""The chunk budget: (resamples in a chunk) x (runs or values), 32 MiB per int64 array.

A chunk of this size takes well under a second, so an interrupt is handled
promptly. Do not change it: the chunk sizes are part of the results' last
bits (see the module docstring).
"""
WORKING_ARRAYS: Final = 3
"""Most chunk-sized arrays alive at once while one chunk is evaluated: the run multiplicities
as drawn, counted and as floats (measured on the example trial: 0.9 to 1.9)."""
ROW_VALUES: Final = 8
"""Values per resample of a chunk beyond its figures and curve points (totals, masks)."""
PER_VALUE_ARRAYS: Final = 80
"""Float64 arrays per carrier (log row) of a condition: its per-run values, its sorted values
and the kernels' copies of them (measured: about 60, at 10 resamples of the example trial)."""
THREAD_BYTES: Final = 32 * 1024
"""Bytes each condition bootstrapped beside the first adds whatever the resamples: its thread's
bookkeeping and the condition's small fixed arrays (measured: about 20 KiB at 10 resamples of
the example trial, where they are most of the peak)."""
_FLOAT: Final = 8
"""Bytes of one float64 bootstrap value."""
_PERCENTILE_TEMPORARIES: Final = 3
"""Per-resample float64 temporaries of a percentile interval: the defined values, numpy's
partition copy, and the NaN masks."""


def bootstrap_memory(
    n_resamples: int,
    *,
    conditions: int,
    width: int,
    metrics: int = len(METRICS) + len(OPTIONAL_METRICS),
    curve_points: int = len(CURVE_THRESHOLDS) + len(LATENCY_PERCENTILES),
    comparisons: int | None = None,
    threads: int = 1,
) -> int:
    """Bytes a bootstrap of ``n_resamples`` over ``conditions`` conditions needs at its peak.

    The defaults describe ``summarize``: ``metrics`` figures per condition,
    ``curve_points`` curve values per resample, one comparison with the
    baseline per other condition (``comparisons``, default ``conditions - 1``),
    each with ``metrics`` bootstrap differences. ``width`` is the most values
    one resample of a condition spans: the rows (carriers) of a condition's
    log for the KPIs, its runs for choice statistics; any upper bound (the
    log's length) will do.

    Kept to the end: ``B`` float64 values per metric of every condition and of
    every comparison (the percentile CIs and p-values need them all). On top
    of these come, at one time, either the last condition's curve values or
    the comparisons' differences; a percentile's temporaries; one chunk: at
    most ``WORKING_ARRAYS`` arrays of ``CHUNK_ELEMENTS`` values (or of
    ``width``, if one resample is wider), or, where resamples are narrow and
    a chunk holds many of them, ``M + K + ROW_VALUES`` values per resample
    of the chunk (its sums and percentiles), whichever is more; and the
    per-carrier bookkeeping. Conditions bootstrapped at once on ``threads``
    threads (``T``) each hold their own curve values, temporaries and chunk,
    and each thread beyond the first ``THREAD_BYTES`` of bookkeeping.
    Not counted: the interpreter and libraries
    (scipy.stats, loaded on first use, takes about 85 MiB; numba, where the
    compiled kernels run, some more) and a few MiB of fixed bookkeeping
    (``PERCENTILE_ROWS``), which every command pays whatever it asks::

        8 * B * (C * M + max(T * K, P * M) + 3 * T)
          + 8 * T * max(WORKING_ARRAYS * min(B * width, max(CHUNK_ELEMENTS, width)),
                        (M + K + ROW_VALUES) * min(B, CHUNK_ELEMENTS // width))
          + 8 * PER_VALUE_ARRAYS * C * width + (T - 1) * THREAD_BYTES

    >>> from swarmtag._resources import format_bytes
    >>> format_bytes(bootstrap_memory(1_000_000_000, conditions=3, width=100))
    '529.1 GiB'
    >>> format_bytes(bootstrap_memory(10_000, conditions=2, width=100))
    '27.7 MiB'
    """
    others = conditions - 1 if comparisons is None else comparisons
    kept = conditions * metrics
    transient = max(threads * curve_points, others * metrics) + threads * _PERCENTILE_TEMPORARIES
    chunk = min(n_resamples * width, max(CHUNK_ELEMENTS, width))
    rows = min(n_resamples, max(1, CHUNK_ELEMENTS // max(1, width)))  # resamples in a chunk
    working = max(WORKING_ARRAYS * chunk, (metrics + curve_points + ROW_VALUES) * rows)
    bookkeeping = PER_VALUE_ARRAYS * conditions * width
    per_request = n_resamples * (kept + transient) + threads * working + bookkeeping
    return _FLOAT * per_request + (threads - 1) * THREAD_BYTES


def condition_seed_sequence(seed: int, condition: str) -> np.random.SeedSequence:
    """The seed sequence of a condition's bootstrap: master seed + digest of the condition name.

    >>> condition_seed_sequence(0, "proximity").spawn_key == condition_seed_sequence(
    ...     0, "proximity").spawn_key
    True
    """
    check_int("seed", seed, low=0, high=MAX_SEED, error=StatisticsError)
    check_text("condition", condition, error=StatisticsError)
    digest = hashlib.sha256(condition.encode("utf-8")).digest()
    return np.random.SeedSequence(seed, spawn_key=(int.from_bytes(digest[:8], "little"),))


def condition_generator(seed: int, condition: str) -> np.random.Generator:
    """A fresh generator for a condition's bootstrap (see ``condition_seed_sequence``)."""
    return np.random.default_rng(condition_seed_sequence(seed, condition))


@cache
def _blas_controller() -> Any:  # noqa: ANN401 - threadpoolctl ships no type information
    """The controller (threadpoolctl's) of the BLAS libraries loaded, numpy's among them; once.

    Making one walks every shared library of the process (a few ms and a few
    hundred kB); limiting through it costs microseconds. Made on first use,
    after numpy, so it holds numpy's OpenBLAS, the one the products call.
    """
    from threadpoolctl import ThreadpoolController  # type: ignore[import-untyped]  # noqa: PLC0415

    return ThreadpoolController()


@contextmanager
def one_blas_thread() -> Iterator[None]:
    """Run the block with BLAS on one thread: the resamples' products are too small for more.

    A product of a chunk's multiplicities with the per-run values (``B x R``
    by ``R x k``, R about a hundred) takes milliseconds; OpenBLAS would split
    it over every core and its threads then spin waiting for the next one,
    burning about as much CPU time again as the statistics themselves. One
    thread computes each product element the same way (the split is over
    rows), so the numbers are the same bits.
    """
    with _blas_controller().limit(limits=1, user_api="blas"):
        yield


def multiplicities(
    draws: NDArray[np.int64], n_runs: int, *, compiled: bool = False
) -> NDArray[np.int64]:
    """How often each run appears in each resample: ``(B, R)`` draws to ``(B, R)`` counts.

    ``compiled`` counts with the compiled kernels (numba), a pass instead of
    a ``bincount`` over shifted copies: the same integers.

    >>> multiplicities(np.array([[0, 0, 2], [1, 2, 0]]), 3)
    array([[2, 0, 1],
           [1, 1, 1]])
    """
    if compiled:
        return count_draws(draws, n_runs)
    n_resamples = draws.shape[0]
    flat = (draws + n_runs * np.arange(n_resamples, dtype=np.int64)[:, None]).ravel()
    counts = np.bincount(flat, minlength=n_resamples * n_runs)
    return counts.reshape(n_resamples, n_runs).astype(np.int64, copy=False)


def iter_multiplicities(
    rng: np.random.Generator,
    n_runs: int,
    n_resamples: int,
    *,
    width: int,
    chunk_elements: int = CHUNK_ELEMENTS,
    compiled: bool = False,
) -> Iterator[NDArray[np.int64]]:
    """Multiplicity rows for ``n_resamples`` resamples of ``n_runs`` runs, in chunks.

    Chunks hold about ``chunk_elements / width`` resamples, where ``width``
    is the widest per-resample array the caller builds. The draws are the
    same whatever the chunk size: the generator hands out one stream (the
    default ``int64`` dtype; the 8- and 16-bit ones would not, see the
    module docstring). ``compiled``: count them as ``multiplicities`` does.
    """
    rows = max(1, min(n_resamples, chunk_elements // max(1, width, n_runs)))
    done = 0
    while done < n_resamples:
        checkpoint()  # a Ctrl-C that numpy swallowed in the last chunk ends the bootstrap here
        take = min(rows, n_resamples - done)
        draws = rng.integers(0, n_runs, size=(take, n_runs))
        yield multiplicities(draws, n_runs, compiled=compiled)
        done += take


def resampled_percentiles(
    values: NDArray[np.float64],
    groups: NDArray[np.intp],
    weights: NDArray[np.int64],
    percentiles: Sequence[float],
    *,
    compiled: bool | None = None,
    out: NDArray[np.float64] | None = None,
) -> NDArray[np.float64]:
    """Percentiles of each resample's pooled values: ``(B, Q)``, NaN where a resample is empty.

    ``values`` are sorted ascending and ``groups`` give each value's run;
    ``weights`` is ``(B, R)``: how often each run is in each resample. Each
    resample's size gives numpy's two order-statistic ranks and weight per
    percentile (``latency.interpolation_points``), found in the once-sorted
    values, numpy or compiled (``compiled``, see ``swarmtag.analysis._kernels``:
    the same bits either way). ``out``, a ``(B, Q)`` array (a strided view
    will do), receives the result.

    >>> values, groups = np.array([1.0, 2.0, 4.0]), np.array([0, 1, 0])
    >>> resampled_percentiles(values, groups, np.array([[2, 0], [0, 2], [1, 1]]), [50])
    array([[2.5],
           [2. ],
           [2. ]])
    """
    result = np.empty((weights.shape[0], len(percentiles))) if out is None else out
    weighted_percentiles(values, groups, weights, percentiles, out=result, compiled=compiled)
    return result
