"""The bootstrap's per-resample work, in numpy or compiled: weighted ranks and KM crossings.

A bootstrap resample of runs is a row of run multiplicities (weights). Both
kernels take the condition's values sorted once, with each value's run, and
answer for every row at once:

- ``weighted_percentiles``: percentiles of the resample's pooled sample
  (the sample in which each run's values appear as often as the run was
  drawn), from the ranks' positions in the sorted values
  (``weighted_positions``);
- ``km_reached``: the first distinct value at which the resample's
  Kaplan-Meier CDF reaches a level.

Each exists twice with the same results: numpy (vectorised over resamples, in
cache-sized blocks of rows) and numba (``swarmtag.analysis._compiled``: one
resample at a time, no per-resample arrays). Both do every float operation
(interpolation, the Kaplan-Meier product) as numpy's own functions do, in
the same order, so the choice changes no bit. numba is used where it is
installed and the work pays for it (``use_compiled``); ``compiled=`` forces
the choice (tests). ``count_draws`` is the compiled twin of
``resampling.multiplicities``: the run multiplicities of the draws.
"""

from __future__ import annotations

import importlib
import importlib.util
import sys
from collections.abc import Sequence
from types import ModuleType
from typing import Final

import numpy as np
from numpy.typing import NDArray

from swarmtag.analysis.latency import interpolation_points, lerp

__all__ = [
    "BLOCK_ELEMENTS",
    "COMPILE_WORTH",
    "LOADED_WORTH",
    "PERCENTILE_ROWS",
    "count_draws",
    "km_reached",
    "numba_available",
    "rank_targets",
    "use_compiled",
    "weighted_percentiles",
    "weighted_positions",
]

LOADED_WORTH: Final = 1 << 24
"""Resamples x values from which the compiled kernels run where numba is loaded already.

Their first call in a process loads their machine code (a tenth of a second or so);
the numpy kernels do this much work in about that time.
"""
COMPILE_WORTH: Final = 1 << 26
"""Resamples x values from which importing numba and starting its compiler (about a
second, more on the very first run: compilation) pays for itself."""
BLOCK_ELEMENTS: Final = 1 << 16
"""Rows x values of one numpy block: 512 KiB per int64 array, so the passes stay in cache."""
PERCENTILE_ROWS: Final = 2048
"""Resamples whose percentiles numpy finds at once: their ranks, positions and weights (about
200 values each, 3 MiB) are the only per-resample bookkeeping beyond a chunk's arrays."""


def numba_available() -> bool:
    """Whether numba (the ``fast`` extra) is installed."""
    return "numba" in sys.modules or importlib.util.find_spec("numba") is not None


def use_compiled(work: int) -> bool:
    """Whether the compiled kernels should run ``work`` (resamples x values) here.

    Yes where numba is installed and the work is at least ``LOADED_WORTH`` if
    numba is loaded already (``swarmtag simulate`` with the fast backend), else
    ``COMPILE_WORTH``; both kinds of kernel give the same results.
    """
    if "numba" in sys.modules:
        return work >= LOADED_WORTH
    return work >= COMPILE_WORTH and numba_available()


def _compiled_module(compiled: bool | None, work: int) -> ModuleType | None:
    """The compiled kernels if they are to run (``compiled``, else ``use_compiled``)."""
    if compiled is None:
        compiled = use_compiled(work)
    # numba is an extra: the module that needs it is imported only when it is used.
    return importlib.import_module("swarmtag.analysis._compiled") if compiled else None


def count_draws(draws: NDArray[np.int64], n_runs: int) -> NDArray[np.int64]:
    """How often each run was drawn in each row, with the compiled kernels: ``(B, R)``.

    ``resampling.multiplicities`` with ``compiled=True``; numba must be installed.
    """
    counts = np.zeros((draws.shape[0], n_runs), dtype=np.int64)
    kernels = importlib.import_module("swarmtag.analysis._compiled")
    kernels.count_draws(np.ascontiguousarray(draws, dtype=np.int64), counts)
    return counts


def _block_rows(width: int) -> int:
    return max(1, BLOCK_ELEMENTS // max(1, width))


def weighted_positions(
    groups: NDArray[np.intp], weights: NDArray[np.int64], ranks: NDArray[np.int64]
) -> NDArray[np.int64]:
    """Where each rank of each resample's pooled sample falls in the sorted values: ``(B, K)``.

    ``groups`` gives the run of each sorted value, ``weights`` is ``(B, R)``
    (how often each run is in each resample) and ``ranks`` ``(B, K)``
    0-based ranks, each below its row's total weight. The answer is the first
    value whose cumulative weight exceeds the rank (numpy, blocks of rows).

    >>> weighted_positions(np.array([0, 1, 0]), np.array([[2, 0], [1, 1]]), np.array([[1, 3],
    ...     [0, 1]]))
    array([[0, 2],
           [0, 1]])
    """
    out: NDArray[np.int64] = np.empty(ranks.shape, dtype=np.int64)
    if out.size == 0:
        return out
    rows = _block_rows(len(groups))
    for start in range(0, out.shape[0], rows):
        block = slice(start, start + rows)
        cumulative = np.cumsum(weights[block][:, groups], axis=1)
        # One sorted search over all rows: shift row b by b * stride so rows never overlap.
        stride = int(cumulative[:, -1].max()) + 1
        shift = np.arange(cumulative.shape[0], dtype=np.int64) * stride
        cumulative += shift[:, None]
        flat = cumulative.ravel()
        base = np.arange(cumulative.shape[0], dtype=np.int64) * len(groups)
        for column in range(out.shape[1]):
            found = np.searchsorted(flat, ranks[block, column] + shift, side="right")
            out[block, column] = found - base
    return out


def weighted_percentiles(
    values: NDArray[np.float64],
    groups: NDArray[np.intp],
    weights: NDArray[np.int64],
    percentiles: Sequence[float],
    *,
    out: NDArray[np.float64],
    compiled: bool | None = None,
) -> None:
    """Percentiles of each resample's pooled sample into ``out`` ``(B, Q)``; NaN if it is empty.

    ``values`` are sorted ascending with each one's run (``groups``);
    ``weights`` is ``(B, R)``. numpy's default method bit for bit: each
    resample's size gives two order-statistic ranks and a weight per
    percentile (``latency.interpolation_points``), the ranks are found in the
    once-sorted values and interpolated (``latency.lerp``).
    """
    weights = np.ascontiguousarray(weights, dtype=np.int64)
    groups = np.ascontiguousarray(groups, dtype=np.intp)
    fractions = np.asarray(percentiles, dtype=np.float64)
    per_run = np.bincount(groups, minlength=weights.shape[1]).astype(np.int64)
    if values.size == 0:
        out[...] = np.nan
        return
    kernels = _compiled_module(compiled, weights.shape[0] * values.size)
    if kernels is not None:
        columns = np.argsort(fractions, kind="stable").astype(np.int64)
        ascending = np.true_divide(fractions[columns], 100, dtype=np.float64)
        values = np.ascontiguousarray(values, dtype=np.float64)
        block = np.empty((min(PERCENTILE_ROWS, weights.shape[0]), fractions.size))
        for start in range(0, weights.shape[0], PERCENTILE_ROWS):  # one C-ordered out: one build
            rows = weights[start : start + PERCENTILE_ROWS]
            done = block[: rows.shape[0]]
            kernels.weighted_percentiles(values, groups, per_run, rows, ascending, columns, done)
            out[start : start + rows.shape[0]] = done
        return
    totals = weights @ per_run  # integers: exact
    out[...] = np.nan
    filled = np.flatnonzero(totals > 0)
    for start in range(0, filled.size, PERCENTILE_ROWS):  # bounded bookkeeping per block
        rows = filled[start : start + PERCENTILE_ROWS]
        lower, upper, gamma = interpolation_points(totals[rows, None], fractions)
        positions = weighted_positions(groups, weights[rows], np.concatenate([lower, upper], 1))
        low, high = values[positions[:, : fractions.size]], values[positions[:, fractions.size :]]
        out[rows] = lerp(low, high, gamma)


_UNIT: Final = 2.0**-53
"""Unit roundoff of float64: one IEEE operation errs by at most this, relatively."""


def rank_targets(totals: NDArray[np.int64], level: float, n_distinct: int) -> NDArray[np.int64]:
    """Per resample, the death count at which its KM CDF reaches ``level`` while uncensored; -1.

    Until the first censored value, the product-limit CDF is exactly ``c / n``
    (``c`` deaths so far, ``n`` values: the product telescopes), so it first
    reaches ``level`` at the ``ceil(level * n)``-th death. The float product
    errs by at most ``(2 D + 1)`` roundoffs (D factors of one division and
    one product each, then ``1 - S``), so the ranks decide exactly what the
    product decides unless ``level * n`` lies within that error of an
    integer: such resamples (and all for a level that is not positive) get
    -1, for the product itself.
    """
    n = totals.astype(np.float64)
    scaled = level * n
    error = 1.02 * (2 * n_distinct + 1) * _UNIT * n + 2 * _UNIT * scaled
    above, below = np.ceil(scaled), np.floor(scaled)
    clear = (scaled - below > error) & (above - scaled > error) & (totals > 0)
    if not level > 0:
        clear[:] = False
    return np.where(clear, above, -1).astype(np.int64)


def km_reached(
    values: NDArray[np.float64],
    runs: NDArray[np.intp],
    observed: NDArray[np.bool_],
    weights: NDArray[np.int64],
    level: float,
    *,
    compiled: bool | None = None,
) -> NDArray[np.int64]:
    """For each resample, where in ``values`` its KM CDF first reaches ``level``; -1 if never.

    ``values`` are sorted ascending with their runs (``runs``) and whether
    each is an event (``observed``). The product-limit estimate runs over
    every distinct value with weighted counts at risk and weighted deaths,
    ``S = cumprod((n - d) / max(n, 1) + (n == 0))``, reached where
    ``1 - S >= level``; the answer indexes a value equal to that distinct one.
    Where ranks decide it exactly (``rank_targets``; no censored value before
    the crossing) the crossing is the weighted order statistic of the deaths,
    else the product is computed as written.
    """
    values = np.ascontiguousarray(values, dtype=np.float64)
    runs = np.ascontiguousarray(runs, dtype=np.intp)
    observed = np.ascontiguousarray(observed, dtype=np.bool_)
    weights = np.ascontiguousarray(weights, dtype=np.int64)
    out = np.full(weights.shape[0], -1, dtype=np.int64)
    if out.size == 0 or values.size == 0:
        return out
    _, first = np.unique(values, return_index=True)
    starts = np.append(first, values.size).astype(np.int64)
    per_run = np.bincount(runs, minlength=weights.shape[1]).astype(np.int64)
    targets = rank_targets(weights @ per_run, level, first.size)
    kernels = _compiled_module(compiled, weights.shape[0] * values.size)
    if kernels is not None:
        kernels.km_reached(values, runs, observed, starts, per_run, weights, targets, level, out)
        return out
    exact = _km_by_ranks(values, runs, observed, weights, targets=targets, out=out)
    if exact.size:
        out[exact] = _km_product(runs, observed, starts, weights[exact], level)
    return out


def _km_by_ranks(
    values: NDArray[np.float64],
    runs: NDArray[np.intp],
    observed: NDArray[np.bool_],
    weights: NDArray[np.int64],
    *,
    targets: NDArray[np.int64],
    out: NDArray[np.int64],
) -> NDArray[np.intp]:
    """``km_reached`` where ranks decide (into ``out``); the rows left for the product."""
    events = np.flatnonzero(observed)
    deaths = weights @ np.bincount(runs[events], minlength=weights.shape[1])
    ranked = np.flatnonzero((targets >= 0) & (targets <= deaths))
    first_censored = np.full(weights.shape[1], np.inf)  # of each run
    np.minimum.at(first_censored, runs[~observed], values[~observed])
    at = weighted_positions(runs[events], weights[ranked], (targets[ranked] - 1)[:, None])
    crossing = events[at[:, 0]]
    censored_first = np.where(weights[ranked] > 0, first_censored, np.inf).min(
        axis=1, initial=np.inf
    )
    decided = values[crossing] <= censored_first
    out[ranked[decided]] = crossing[decided]
    left = np.ones(weights.shape[0], dtype=bool)
    left[ranked[decided]] = False
    return np.flatnonzero(left)


def _km_product(
    runs: NDArray[np.intp],
    observed: NDArray[np.bool_],
    starts: NDArray[np.int64],
    weights: NDArray[np.int64],
    level: float,
) -> NDArray[np.int64]:
    """The product-limit crossing of each resample, as written (numpy, blocks of rows)."""
    out = np.full(weights.shape[0], -1, dtype=np.int64)
    first = starts[:-1]
    last = starts[1:] - 1
    rows = _block_rows(runs.size)
    for start in range(0, weights.shape[0], rows):
        block = slice(start, start + rows)
        counts = weights[block][:, runs]
        at_risk = np.cumsum(counts[:, ::-1], axis=1)[:, ::-1][:, first]  # weight at or after
        counts *= observed
        deaths = np.diff(np.cumsum(counts, axis=1)[:, last], axis=1, prepend=0)
        ratio = (at_risk - deaths) / np.maximum(at_risk, 1) + (at_risk == 0)
        reached = 1 - np.cumprod(ratio, axis=1) >= level
        hit = reached.any(axis=1)
        out[block][hit] = first[reached[hit].argmax(axis=1)]
    return out
