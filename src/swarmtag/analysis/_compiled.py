"""The bootstrap's per-resample loops compiled with numba (the ``fast`` extra).

``swarmtag.analysis._kernels`` calls these where numba is installed and the
work pays for loading it; its numpy functions of the same names give the same
results. Each loop walks one resample's pooled, once-sorted values with the
resample's run multiplicities as weights, so no per-resample array is built:

- ``weighted_percentiles``: percentiles of a resample's pooled sample,
  numpy's default method in its very operations (``fastmath`` off, so no
  contraction or reassociation: the same bits);
- ``count_draws``: how often each run was drawn in each resample;
- ``km_reached``: the first distinct value at which a resample's
  Kaplan-Meier CDF reaches a level: by counting deaths where that decides
  it exactly (``_kernels.rank_targets``), else with the product-limit
  factors multiplied in order, one IEEE operation each as numpy does them:
  bit for bit the numpy result.

``cache=True`` keeps the machine code beside the sources (a later process
loads it in well under a second); ``nogil=True`` lets threads run them at once.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any, TypeVar

import numba
import numpy as np
from numpy.typing import NDArray

__all__ = ["count_draws", "km_reached", "weighted_percentiles"]

_F = TypeVar("_F", bound=Callable[..., Any])


def _compiled(function: _F) -> _F:
    """``function`` compiled: nopython, cached, IEEE arithmetic, no GIL."""
    dispatcher: Any = numba.njit(cache=True, nogil=True, fastmath=False, error_model="numpy")
    compiled: _F = dispatcher(function)
    return compiled


@_compiled
def count_draws(draws: NDArray[np.int64], counts: NDArray[np.int64]) -> None:
    """``counts[b, run]`` += how often ``run`` is among ``draws[b]`` (``counts`` starts at 0)."""
    for row in range(draws.shape[0]):
        for column in range(draws.shape[1]):
            counts[row, draws[row, column]] += 1


@_compiled
def _interpolation_ranks(
    last: int, fractions: NDArray[np.float64], ranks: NDArray[np.int64], gammas: NDArray[np.float64]
) -> None:
    """``latency.interpolation_points`` of a sample of ``last + 1``: ranks in pairs, weights."""
    for point in range(fractions.size):
        virtual = last * fractions[point]
        lower = np.floor(virtual)
        gammas[point] = virtual - lower
        lower_index = int(lower)
        upper_index = lower_index + 1
        if virtual >= last:
            lower_index = last
            upper_index = last
        ranks[2 * point] = lower_index
        ranks[2 * point + 1] = upper_index


@_compiled
def _rank_order(ranks: NDArray[np.int64], order: NDArray[np.int64]) -> None:
    """``order``: the ranks' indices by rank (an insertion sort: they come nearly in order)."""
    for slot in range(ranks.size):
        rank = ranks[slot]
        before = slot - 1
        while before >= 0 and ranks[order[before]] > rank:
            order[before + 1] = order[before]
            before -= 1
        order[before + 1] = slot


@_compiled
def _find_ranks(
    groups: NDArray[np.intp],
    row_weights: NDArray[np.int64],
    ranks: NDArray[np.int64],
    order: NDArray[np.int64],
    found: NDArray[np.int64],
) -> None:
    """``found[k]``: the first value whose cumulative weight exceeds ``ranks[k]`` (one walk)."""
    cumulative = 0
    pending = 0
    next_rank = ranks[order[0]]
    for index in range(groups.size):
        cumulative += row_weights[groups[index]]
        while cumulative > next_rank:
            found[order[pending]] = index
            pending += 1
            if pending == ranks.size:
                return
            next_rank = ranks[order[pending]]


@_compiled
def weighted_percentiles(  # noqa: PLR0917 - numba takes no keyword-only arguments
    values: NDArray[np.float64],
    groups: NDArray[np.intp],
    per_run: NDArray[np.int64],
    weights: NDArray[np.int64],
    fractions: NDArray[np.float64],
    columns: NDArray[np.int64],
    out: NDArray[np.float64],
) -> None:
    """``out[b, columns[j]]``: the ``fractions[j] * 100``-th percentile of resample b's pool.

    Value ``i`` (sorted ascending) belongs to run ``groups[i]``, which holds
    ``per_run[run]`` values and appears ``weights[b, run]`` times in resample
    ``b``. numpy's default method, operation for operation: position
    ``(n - 1) * fraction``, its floor and the next order statistic (both
    clipped to ``n - 1``), found in one walk over the sorted values with the
    ranks in order (``fractions`` ascending keeps them nearly so), then
    ``latency.lerp``. NaN where the resample is empty.
    """
    ranks = np.empty(2 * fractions.size, np.int64)
    order = np.empty(2 * fractions.size, np.int64)
    found = np.empty(2 * fractions.size, np.int64)
    gammas = np.empty(fractions.size)
    for row in range(weights.shape[0]):
        row_weights = weights[row]
        total = 0
        for run in range(per_run.size):
            total += row_weights[run] * per_run[run]
        if total == 0:
            for point in range(fractions.size):
                out[row, columns[point]] = np.nan
            continue
        _interpolation_ranks(total - 1, fractions, ranks, gammas)
        _rank_order(ranks, order)
        _find_ranks(groups, row_weights, ranks, order, found)
        for point in range(fractions.size):  # latency.lerp
            low = values[found[2 * point]]
            high = values[found[2 * point + 1]]
            difference = high - low
            if gammas[point] >= 0.5:
                out[row, columns[point]] = high - difference * (1 - gammas[point])
            else:
                out[row, columns[point]] = low + difference * gammas[point]


_UNDECIDED = -2
"""What ``_crossing_by_rank`` returns when a censored value comes first: the product decides."""


@_compiled
def _crossing_by_rank(
    values: NDArray[np.float64],
    runs: NDArray[np.intp],
    observed: NDArray[np.bool_],
    weights: NDArray[np.int64],
    target: int,
) -> int:
    """The value at which the weighted death count reaches ``target``, if no censored one is first.

    -1 if it is never reached and the resample has no censored value (then
    the CDF never reaches the level); ``_UNDECIDED`` otherwise.
    """
    deaths = 0
    first_censored = np.inf
    for index in range(values.size):
        weight = weights[runs[index]]
        if observed[index]:  # no test of the weight here: a mispredicted branch costs more
            deaths += weight
            if deaths >= target:
                return index if values[index] <= first_censored else _UNDECIDED
        elif weight > 0 and values[index] < first_censored:
            first_censored = values[index]
    return -1 if first_censored == np.inf else _UNDECIDED


@_compiled
def _crossing_by_product(  # noqa: PLR0917 - numba takes no keyword-only arguments
    runs: NDArray[np.intp],
    observed: NDArray[np.bool_],
    starts: NDArray[np.int64],
    at_risk: int,
    weights: NDArray[np.int64],
    level: float,
) -> int:
    """Where the product-limit CDF first reaches ``level`` (a value's index), -1 if never."""
    product = 1.0
    for index in range(starts.size - 1):
        here = 0
        deaths = 0
        for value in range(starts[index], starts[index + 1]):
            weight = weights[runs[value]]
            here += weight
            if observed[value]:
                deaths += weight
        # numpy's very operations, factors of exactly 1 included (cheaper than a branch)
        ratio = (at_risk - deaths) / max(at_risk, 1) + (1.0 if at_risk == 0 else 0.0)
        product = product * ratio
        if 1.0 - product >= level:
            return int(starts[index])
        at_risk -= here
    return -1


@_compiled
def km_reached(  # noqa: PLR0917 - numba takes no keyword-only arguments
    values: NDArray[np.float64],
    runs: NDArray[np.intp],
    observed: NDArray[np.bool_],
    starts: NDArray[np.int64],
    per_run: NDArray[np.int64],
    weights: NDArray[np.int64],
    targets: NDArray[np.int64],
    level: float,
    out: NDArray[np.int64],
) -> None:
    """``out[b]``: where in ``values`` resample b's Kaplan-Meier CDF first reaches ``level``; -1.

    The sorted values ``starts[i]:starts[i + 1]`` share the ``i``-th distinct
    value; ``per_run`` counts the values of each run. Where ``targets[b]``
    is not -1 (``_kernels.rank_targets``) the crossing is the death at which
    the weighted death count reaches it, provided no censored value of the
    resample comes before; otherwise the product-limit walk decides, over
    every distinct value as numpy's ``cumprod`` does.
    """
    for row in range(weights.shape[0]):
        row_weights = weights[row]
        found = _UNDECIDED
        if targets[row] >= 0:
            found = _crossing_by_rank(values, runs, observed, row_weights, targets[row])
        if found == _UNDECIDED:
            at_risk = 0
            for run in range(per_run.size):
                at_risk += row_weights[run] * per_run[run]
            found = _crossing_by_product(runs, observed, starts, at_risk, row_weights, level)
        out[row] = found
